# Front profiles at the predicted speeds: psi along the system over one
# wavelength, and the phase portrait f'(z) against f(z) (data: bkfront profile).
minwidth = 1400
load plotdir.'/common.gp'
f = word(files, 1)
nn = words(values)
set multiplot layout 1, 2 title titled('Front profiles', f, 'gamma c nu S')
set xlabel 'position x (one wavelength S/n)'
set ylabel '{/Symbol y} = f(z)'
set key bottom right
plot for [i=1:nn] f using (column('n') == word(values, i) + 0 ? column('x') : NaN):'f' \
       with lines lw 2 lc rgb color(i) title sprintf('n = %s', word(values, i))
set xlabel 'f'
set ylabel "f'"
set key top left
plot for [i=1:nn] f using (column('n') == word(values, i) + 0 ? column('f') : NaN):'fprime' \
       with lines lw 2 lc rgb color(i) title sprintf('n = %s', word(values, i))
unset multiplot
