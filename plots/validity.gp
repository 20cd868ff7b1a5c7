# The validity map: log10 of the relative error of each asymptotic formula
# for T over the (mu, nu) plane (data: bkfront asymptotics --grid).  The
# three panels share one colour scale, spanning the data, and one bar.
minwidth = 1500
load plotdir.'/common.gp'
f = word(files, 1)
cap(e) = (e > 0 ? log10(e) : -16)
elo = 0
ehi = -16
do for [col in 'rel_err_leading rel_err_corrected rel_err_small'] {
    stats f using (cap(column(col))) nooutput name 'E'
    elo = E_min < elo ? E_min : elo
    ehi = E_max > ehi ? E_max : ehi
}
set cbrange [floor(elo) : ceil(ehi > 0 ? ehi : 0)]
# equal panels, the bar right of the last
set multiplot layout 1, 3 margins 0.05, 0.91, 0.14, 0.86 spacing 0.05 \
  title (title ne '' ? title : 'log_{10} of the relative error of the asymptotic period')
set xlabel 'log_{10} {/Symbol m}'
set ylabel '{/Symbol n}'
set autoscale xfix
set autoscale yfix
set cblabel 'log_{10} |T_{formula} - T| / T'
set palette defined (0 '#00441b', 3 '#41ab5d', 6 '#f7fcb9', 9 '#fd8d3c', 12 '#67000d')
set key off
set grid noxtics noytics
unset colorbox
set title 'leading: k({/Symbol n}) {/Symbol m}'
plot f using (log10(column('mu'))):'nu':(cap(column('rel_err_leading'))) with image
set title 'corrected large-{/Symbol m}'
unset ylabel
plot f using (log10(column('mu'))):'nu':(cap(column('rel_err_corrected'))) with image
set title 'small {/Symbol m}: 2{/Symbol p}(1 + s_2 {/Symbol m}^2)'
set colorbox user origin screen 0.925, screen 0.14 size screen 0.012, screen 0.72
plot f using (log10(column('mu'))):'nu':(cap(column('rel_err_small'))) with image
unset multiplot
