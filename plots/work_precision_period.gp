# Work-precision of T(mu, nu): achieved relative error against CPU seconds per
# call, for the leading term, the corrected asymptotics and shooting with rk8pd
# and bsimp at tol 1e-2 .. 1e-12.  Data: bkfront bench (make bench writes
# plots/out/work_precision.tsv).  Run from the repository root:
#     gnuplot plots/work_precision_period.gp
set terminal pngcairo size 1600,800 font ",10"
set output 'plots/out/work_precision_period.png'
set datafile separator "\t"
set datafile missing "nan"
data = 'plots/out/work_precision.tsv'
set logscale xy
set format x "10^{%L}"
set format y "10^{%L}"
set xlabel "CPU time per call [s]"
set ylabel "achieved relative error of T"
set key bottom left box opaque font ",8"
set grid
sel(case, m) = (strcol(1) eq "period" && strcol(2) eq case && strcol(3) eq m && strcol(10) eq "ok" && $6 > 0) ? $6 : NaN
cases = "mu=1,nu=0 mu=10,nu=0 mu=100,nu=0 mu=10000,nu=0 mu=1,nu=-0.96 mu=10,nu=-0.96 mu=100,nu=-0.96 mu=10000,nu=-0.96"
set multiplot layout 2,4 title "Work-precision of T(mu, nu) (points of a line: tol 1e-2 .. 1e-12; errors at rounding, 0, are not drawn)"
do for [i=1:words(cases)] {
    c = word(cases, i)
    set label 1 c at graph 0.5, 0.93 center noenhanced front
    plot data using 8:(sel(c, "rk8pd")) with linespoints pt 7 ps 0.6 title "shooting, rk8pd", \
         data using 8:(sel(c, "bsimp")) with linespoints pt 5 ps 0.6 title "shooting, bsimp", \
         data using 8:(sel(c, "leading")) with points pt 9 ps 1.5 title "leading k mu", \
         data using 8:(sel(c, "asymptotic")) with points pt 11 ps 1.5 title "corrected asymptotics"
}
unset multiplot
