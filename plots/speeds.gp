# Allowed front speeds v_n against n: every root of the speed condition,
# the large-mu quantization S/(n k gamma) and the sonic line v = c
# (data: bkfront speeds).  The ranges are the data's: every root, every
# v_asym and c in view, whatever the parameters.  A refused root (flags
# refused, v nan: not had to --tol) has no point: nan is invalid data, which
# stats and plot skip; the figure says how many were left out.
load plotdir.'/common.gp'
f = word(files, 1)
set title titled('Allowed front speeds', f, 'gamma c nu S')
set xlabel 'number of fronts n'
set ylabel 'front speed v'
set key top right
cs = input(f, 'c') ne '' ? real(input(f, 'c')) : c
stats f using 'v' nooutput name 'V'
stats f using 'v_asym' nooutput name 'VA'
stats f using 'n' nooutput name 'N'
ylo = cs < V_min ? cs : V_min
yhi = VA_max > V_max ? VA_max : V_max
set logscale y
ylo = ylo / (yhi / ylo)**0.06
yhi = yhi * (yhi / ylo)**0.06
set yrange [ylo:yhi]
call plotdir.'/logtics.gp' 'y' sprintf('%.17g', ylo) sprintf('%.17g', yhi)
set xrange [0.5 : N_max + 0.5]
if (N_max > 20) { set xtics autofreq } else { set xtics 1 }
refused = int(system(sprintf("grep -c '^# refused: ' '%s'", f)))
if (refused > 0) {
    set label 1 sprintf('%d root%s refused (not had to the tolerance): no point', \
        refused, refused > 1 ? 's' : '') at graph 0.98, graph 0.82 right front
}
plot f using 'n':'v_asym' with linespoints dt 2 pt 6 lc rgb '#777777' \
       title 'S / (n k({/Symbol n}) {/Symbol g})', \
     f using 'n':'v' with points pt 7 ps 1.2 lc rgb '#d62728' title 'numerical v_n', \
     cs with lines lc rgb '#1f77b4' lw 2 title 'sound speed c'
