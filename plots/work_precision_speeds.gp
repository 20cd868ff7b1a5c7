# Work-precision of the speeds table (gamma 2, c 0.3, nu -0.96, S 20): largest
# relative error of v over the roots against CPU seconds for the whole table,
# at tol 1e-4 .. 1e-12.  Data: bkfront bench.  Run from the repository root:
#     gnuplot plots/work_precision_speeds.gp
set terminal pngcairo size 800,600 font ",10"
set output 'plots/out/work_precision_speeds.png'
set datafile separator "\t"
set datafile missing "nan"
data = 'plots/out/work_precision.tsv'
set logscale xy
set format y "10^{%L}"
set xlabel "CPU time per table [s]"
set ylabel "largest relative error of v"
set title "Work-precision of the speeds table (paper's parameters)"
set key top right box
set grid
sel(col) = (strcol(1) eq "speeds" && strcol(10) eq "ok" && $6 > 0) ? column(col) : NaN
plot data using 8:(sel(6)) with linespoints pt 7 title "achieved error", \
     data using 8:(sel(7)) with linespoints pt 6 dt 2 title "estimated (v_err/v)", \
     data using 8:(sel(6)):(sprintf("%.0e", $4)) with labels offset 3,0.5 notitle
