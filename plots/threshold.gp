# The period-doubling threshold nu_pd and the critical wavenumber q_c
# along c or gamma (data: bkfront floquet --threshold --along).
load plotdir.'/common.gp'
f = word(files, 1)
pname = (param eq 'gamma' ? '{/Symbol g}' : (param eq '' ? 'c' : param))
x = (param eq '' ? 'c' : param)
set title titled('Stability threshold of the global oscillation', f, 'gamma c')
set xlabel pname
set ylabel 'threshold {/Symbol n}_{pd}'
set y2label 'critical wavenumber q_c'
set ytics nomirror
set y2tics
set key top right
# nu_pd does not depend on c (README, Floquet): a flat curve would make
# gnuplot's autoscale zoom into rounding; show it on a sane range instead
stats f using 'nu_pd' nooutput name 'NUPD'
if (NUPD_max - NUPD_min < 1e-3) { \
    mid = 0.5 * (NUPD_max + NUPD_min); set yrange [mid - 0.01 : mid + 0.01] }
plot f using x:'nu_pd' with linespoints pt 7 lw 2 lc rgb '#d62728' title '{/Symbol n}_{pd}', \
     f using x:'q_c' axes x1y2 with linespoints pt 6 dt 2 lc rgb '#1f77b4' title 'q_c'
