# Predicted front speeds against direct simulation (data: bkfront check).
load plotdir.'/common.gp'
f = word(files, 1)
set title (title ne '' ? title : \
  sprintf('Measured against predicted front speed:  {/Symbol g} = %g,  c = %g,  {/Symbol n} = %g,  S = %g', gamma, c, nu, S))
set xlabel 'number of fronts n'
set ylabel '|v_{meas} - v_{pred}| / v_{pred}'
set logscale y
set format y '10^{%T}'
set offsets 0.5, 0.5, 0, 0
set key top left
plot f using 'n':(column('stable') == 1 ? abs(column('rel_err')) : NaN) with points pt 7 ps 1.4 \
       lc rgb '#2ca02c' title 'stable front', \
     f using 'n':(column('stable') == 1 ? NaN : abs(column('rel_err'))) with points pt 6 ps 1.4 \
       lc rgb '#d62728' title 'unstable (count or shape changed)', \
     f using 'n':(column('stable') == 1 ? column('v_meas_err')/column('v_pred') : NaN) \
       with points pt 1 lc rgb '#555555' title 'fit uncertainty'
