# Spacetime plot of psi(x, t), time vertical (Fig. 3 and 4b of the paper;
# data: bkfront simulate --spacetime, a gnuplot nonuniform matrix).
load plotdir.'/common.gp'
f = word(files, 1)
set datafile separator whitespace
# the inputs are on the command line of the run's table NAME_diag.tsv
diag = f[1:strlen(f) - 4].'_diag.tsv'
set title titled('{/Symbol y}(x, t)', diag, 'gamma c nu S')
set xlabel 'position x'
set ylabel 'time t'
set cblabel '{/Symbol y}'
set palette defined (0 '#08306b', 1 '#2171b5', 2 '#6baed6', 3 '#f7fbff', 4 '#fdae6b', 5 '#d94801', 6 '#7f2704')
set tics out
# x, t and the colours span the data; the colour scale symmetric, white at 0
stats f nonuniform matrix using 3 nooutput name 'PSI'
psimax = abs(PSI_min) > abs(PSI_max) ? abs(PSI_min) : abs(PSI_max)
set cbrange [-psimax : psimax]
set autoscale xfix
set autoscale yfix
set key off
set grid noxtics noytics
plot f nonuniform matrix using 1:2:3 with image
