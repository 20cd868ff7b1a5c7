# Work-precision of the simulation: relative error of the measured speed of a
# seeded n = 4 front (paper's parameters, t in [0, 30]) against CPU seconds of
# the run, for N in {256, 512, 1024} and tol in {1e-5, 1e-7, 1e-9}.
# Data: bkfront bench.  Run from the repository root:
#     gnuplot plots/work_precision_pde.gp
set terminal pngcairo size 800,600 font ",10"
set output 'plots/out/work_precision_pde.png'
set datafile separator "\t"
set datafile missing "nan"
data = 'plots/out/work_precision.tsv'
set logscale xy
set format y "10^{%L}"
set xlabel "CPU time per run [s]"
set ylabel "relative error of the front speed"
set title "Work-precision of the PDE simulation (front n = 4)"
set key top right box
set grid
sel(N) = (strcol(1) eq "pde" && $5 == N && strcol(10) eq "ok" && $6 > 0) ? $6 : NaN
plot for [N in "256 512 1024"] data using 8:(sel(N+0)) with linespoints pt 7 title sprintf("N = %s (tol 1e-5, 1e-7, 1e-9)", N)
