# Predicted front speeds against direct simulation (data: bkfront check).
# Stable fronts (verdict agrees or disagrees) filled, unstable open circles,
# the rest (undecided, conflicts, unresolved: nothing decided the front's
# stability) open triangles; filled circles on the uniform spectral grid,
# squares on the adapted comoving grid (column `grid`).  Room above the data
# for the key (offsets), so it hides no point and not the 1e-6 line.
load plotdir.'/common.gp'
f = word(files, 1)
set title titled('Measured against predicted front speed', f, 'gamma c nu S')
set xlabel 'number of fronts n'
set ylabel '|v_{meas} - v_{pred}| / v_{pred}'
set logscale y
set format y '10^{%T}'
set offsets 0.5, 0.5, graph 0.45, 0
set key top right
# every front's error in view, a disagreeing one too, and the 1e-6 line
set yrange [*:*]
uni(g) = g eq 'uniform'
ok(v) = v eq 'agrees' || v eq 'disagrees'
plot 1e-6 with lines dt 2 lc rgb '#888888' title "the check's default agreement, 1e-6", \
     f using 'n':(ok(strcol('verdict')) && uni(strcol('grid')) ? abs(column('rel_err')) : NaN) \
       with points pt 7 ps 1.4 lc rgb '#2ca02c' title 'stable, uniform spectral grid', \
     f using 'n':(ok(strcol('verdict')) && !uni(strcol('grid')) ? abs(column('rel_err')) : NaN) \
       with points pt 5 ps 1.4 lc rgb '#1f77b4' title 'stable, adapted grid', \
     f using 'n':(strcol('verdict') eq 'unstable' ? abs(column('rel_err')) : NaN) with points pt 6 ps 1.4 \
       lc rgb '#d62728' title 'unstable (by the run or the spectrum)', \
     f using 'n':(ok(strcol('verdict')) || strcol('verdict') eq 'unstable' ? NaN : abs(column('rel_err'))) \
       with points pt 8 ps 1.4 lc rgb '#7f7f7f' title 'undecided, conflicting or unresolved', \
     f using 'n':(ok(strcol('verdict')) ? column('v_meas_err')/column('v_pred') : NaN) \
       with points pt 1 lc rgb '#555555' title 'fit uncertainty'
