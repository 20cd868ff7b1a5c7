# The validity map: log10 of the relative error of each asymptotic formula
# for T over the (mu, nu) plane (data: bkfront asymptotics --grid).
minwidth = 1500
load plotdir.'/common.gp'
f = word(files, 1)
set multiplot layout 1, 3 title (title ne '' ? title : \
  'log_{10} of the relative error of the asymptotic period')
set xlabel 'log_{10} {/Symbol m}'
set ylabel '{/Symbol n}'
set cbrange [-12:0]
set autoscale xfix
set autoscale yfix
set cblabel 'log_{10} |T_{formula} - T| / T'
set palette defined (0 '#00441b', 3 '#41ab5d', 6 '#f7fcb9', 9 '#fd8d3c', 12 '#67000d')
set key off
set grid noxtics noytics
cap(e) = (e > 0 ? log10(e) : -16)
set title 'leading: k({/Symbol n}) {/Symbol m}'
plot f using (log10(column('mu'))):'nu':(cap(column('rel_err_leading'))) with image
set title 'corrected large-{/Symbol m}'
plot f using (log10(column('mu'))):'nu':(cap(column('rel_err_corrected'))) with image
set title 'small {/Symbol m}: 2{/Symbol p}(1 + s_2 {/Symbol m}^2)'
plot f using (log10(column('mu'))):'nu':(cap(column('rel_err_small'))) with image
unset multiplot
