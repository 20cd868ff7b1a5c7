# Re sigma(kappa) of front trains on the infinite line (bkfront stability
# --line): the rightmost sigma against the Bloch number, one curve per
# data file (its n in values); Re sigma = 0 is the stability boundary.
load plotdir.'/common.gp'
set xlabel '{/Symbol k} L / 2{/Symbol p}'
set ylabel 'max Re {/Symbol s}'
set key top right
set xzeroaxis lc rgb '#777777' dt 2 lw 1.5
set title titled('Continuous spectrum on the line', word(files, 1), 'gamma c nu S')
Sv = input(word(files, 1), 'S') ne '' ? real(input(word(files, 1), 'S')) : S
# kappa in units of 2 pi / L, L = S/n
plot for [i = 1:nfiles] word(files, i) using (column('kappa') * Sv / (2 * pi * word(values, i))):'re' \
     with linespoints pt 7 ps 0.5 lw 2 lc rgb color(i) title sprintf('n = %s', word(values, i))
