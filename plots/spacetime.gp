# Spacetime plot of psi(x, t), time vertical (Fig. 3 and 4b of the paper;
# data: bkfront simulate --spacetime, a gnuplot nonuniform matrix).
load plotdir.'/common.gp'
f = word(files, 1)
set datafile separator whitespace
set title (title ne '' ? title : \
  sprintf('{/Symbol y}(x, t):  {/Symbol g} = %g,  c = %g,  {/Symbol n} = %g,  S = %g', gamma, c, nu, S))
set xlabel 'position x'
set ylabel 'time t'
set cblabel '{/Symbol y}'
set palette defined (0 '#08306b', 1 '#2171b5', 2 '#6baed6', 3 '#f7fbff', 4 '#fdae6b', 5 '#d94801', 6 '#7f2704')
set tics out
set xrange [0:S]
set yrange [0:tmax]
set cbrange [-2.2:2.2]
set key off
set grid noxtics noytics
plot f nonuniform matrix using 1:2:3 with image
