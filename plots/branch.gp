# Branches v_n(p) of allowed front speeds by continuation, folds marked
# (data: bkfront branch).
load plotdir.'/common.gp'
colors = '#1f77b4 #2ca02c #d62728 #9467bd #ff7f0e #8c564b'
pname = (param eq 'nu' ? '{/Symbol n}' : (param eq 'gamma' ? '{/Symbol g}' : param))
set title (title ne '' ? title : sprintf('Front-speed branches along %s', pname))
set xlabel pname
set ylabel 'front speed v'
set key top left
plot for [i=1:nfiles] word(files, i) using param:'v' with lines lw 2 \
       lc rgb word(colors, (i-1)%6+1) title sprintf('n = %s', word(values, i)), \
     for [i=1:nfiles] word(files, i) using param:(strcol('point') eq 'fold' ? column('v') : NaN) \
       with points pt 7 ps 1.3 lc rgb 'black' notitle, \
     for [i=1:nfiles] word(files, i) using param:(strcol('point') eq 'sonic' ? column('c') : NaN) \
       with points pt 4 ps 1.5 lc rgb 'black' notitle, \
     NaN with points pt 7 lc rgb 'black' title 'fold', \
     NaN with points pt 4 lc rgb 'black' title 'sonic limit v = c'
