# T(mu) of f'' + mu (f^2-1) f' + f = nu against k mu and the corrected
# asymptotics, and their relative errors (data: bkfront period).
minwidth = 1400
load plotdir.'/common.gp'
set multiplot layout 1, 2 title (title ne '' ? title : 'Period of the rescaled van der Pol cycle')
set logscale xy
set format x '10^{%T}'
set xlabel '{/Symbol m}'
set ylabel 'period T'
set key top left
plot for [i=1:nfiles] word(files, i) using 'mu':'T' with points pt 7 ps 0.6 \
       lc rgb color(i) title sprintf('numerical, {/Symbol n} = %s', word(values, i)), \
     for [i=1:nfiles] word(files, i) using 'mu':'T_asym' with lines dt 2 \
       lc rgb color(i) notitle, \
     for [i=1:nfiles] word(files, i) using 'mu':(column('mu') >= 1 ? column('T_asym2') : NaN) \
       with lines lc rgb color(i) notitle, \
     NaN with lines dt 2 lc rgb 'black' title 'leading k({/Symbol n}) {/Symbol m}', \
     NaN with lines lc rgb 'black' title 'corrected large-{/Symbol m} ({/Symbol m} {/Symbol \263} 1)'
set ylabel 'relative error |T_{asym} - T| / T'
set format y '10^{%T}'
set key bottom left
plot for [i=1:nfiles] word(files, i) using 'mu':(abs(column('T_asym') - column('T'))/column('T')) \
       with lines dt 2 lc rgb color(i) notitle, \
     for [i=1:nfiles] word(files, i) \
       using 'mu':(abs(column('T_asym2') - column('T'))/column('T')) \
       with linespoints pt 7 ps 0.5 lc rgb color(i) \
       title sprintf('{/Symbol n} = %s', word(values, i)), \
     NaN with lines dt 2 lc rgb 'black' title 'leading k({/Symbol n}) {/Symbol m}', \
     NaN with linespoints pt 7 ps 0.5 lc rgb 'black' title 'small-{/Symbol m} ({/Symbol m} < 1), corrected large-{/Symbol m} ({/Symbol m} {/Symbol \263} 1)'
unset multiplot
