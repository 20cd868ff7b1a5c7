# Allowed front speeds v_n against n: every root of the speed condition,
# the large-mu quantization S/(n k gamma) and the sonic line v = c
# (data: bkfront speeds).
load plotdir.'/common.gp'
f = word(files, 1)
set title (title ne '' ? title : \
  sprintf('Allowed front speeds:  {/Symbol g} = %g,  c = %g,  {/Symbol n} = %g,  S = %g', gamma, c, nu, S))
set xlabel 'number of fronts n'
set ylabel 'front speed v'
set key top right
set logscale y
set yrange [0.2:5]
set xrange [0:*]
set offsets 0.5, 0.5, 0, 0
plot f using 'n':'v_asym' with linespoints dt 2 pt 6 lc rgb '#777777' \
       title 'S / (n k({/Symbol n}) {/Symbol g})', \
     f using 'n':'v' with points pt 7 ps 1.2 lc rgb '#d62728' title 'numerical v_n', \
     c with lines lc rgb '#1f77b4' lw 2 title 'sound speed c'
