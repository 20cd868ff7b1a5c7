# Branches v_n(p) of allowed front speeds by continuation, folds marked
# (data: bkfront branch).  With --stability (columns stable, sigma_max, ...)
# stable parts are solid, unstable parts dashed, unresolved ones (and any
# gap between two verdicts) dotted grey, the parameters held fixed in the title and the changes of stability (rows
# of type stability) are marked.
load plotdir.'/common.gp'
pname = (param eq 'nu' ? '{/Symbol n}' : (param eq 'gamma' ? '{/Symbol g}' : param))
set title titled(sprintf('Front-speed branches along %s', pname), word(files, 1), 'gamma c nu S')
set xlabel pname
set ylabel 'front speed v'
set key top left
# The header line (the first that is not a comment) names the columns.
header(f) = system(sprintf("grep -m1 -v '^#' '%s'", f))
stab = strstrt(header(word(files, 1)), "sigma_max") > 0
if (!stab) {
plot for [i=1:nfiles] word(files, i) using param:'v' with lines lw 2 \
       lc rgb color(i) title sprintf('n = %s', word(values, i)), \
     for [i=1:nfiles] word(files, i) using param:(strcol('point') eq 'fold' ? column('v') : NaN) \
       with points pt 7 ps 1.3 lc rgb 'black' notitle, \
     for [i=1:nfiles] word(files, i) using param:(strcol('point') eq 'sonic' ? column('c') : NaN) \
       with points pt 4 ps 1.5 lc rgb 'black' notitle, \
     NaN with points pt 7 lc rgb 'black' title 'fold', \
     NaN with points pt 4 lc rgb 'black' title 'sonic limit v = c'
} else {
# a change of stability belongs to both sides, so the two lines meet there;
# the grey line under the dashed one is wiped white first
on(s) = strcol('stable') eq s || strcol('point') eq 'stability'
plot for [i=1:nfiles] word(files, i) using param:'v' with lines lw 2 dt 3 \
       lc rgb '#777777' notitle, \
     for [i=1:nfiles] word(files, i) using param:(on('yes') ? column('v') : NaN) with lines lw 2 \
       lc rgb color(i) title sprintf('n = %s', word(values, i)), \
     for [i=1:nfiles] word(files, i) using param:(on('no') ? column('v') : NaN) with lines lw 3 \
       lc rgb 'white' notitle, \
     for [i=1:nfiles] word(files, i) using param:(on('no') ? column('v') : NaN) with lines lw 2 \
       dt 2 lc rgb color(i) notitle, \
     for [i=1:nfiles] word(files, i) using param:(strcol('point') eq 'fold' ? column('v') : NaN) \
       with points pt 7 ps 1.3 lc rgb 'black' notitle, \
     for [i=1:nfiles] word(files, i) using param:(strcol('point') eq 'sonic' ? column('c') : NaN) \
       with points pt 4 ps 1.5 lc rgb 'black' notitle, \
     for [i=1:nfiles] word(files, i) \
       using param:(strcol('point') eq 'stability' ? column('v') : NaN) \
       with points pt 13 ps 1.6 lc rgb 'black' notitle, \
     NaN with lines lw 2 lc rgb 'black' title 'stable', \
     NaN with lines lw 2 dt 2 lc rgb 'black' title 'unstable', \
     NaN with lines lw 2 dt 3 lc rgb '#777777' title 'unresolved', \
     NaN with points pt 13 ps 1.6 lc rgb 'black' title 'change of stability', \
     NaN with points pt 7 lc rgb 'black' title 'fold', \
     NaN with points pt 4 lc rgb 'black' title 'sonic limit v = c'
}
