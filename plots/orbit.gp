# The branch of period-doubled orbits (data: bkfront orbit; files: the
# table, then the spacetime field and the multipliers of one orbit, as the
# scene kind `orbit` writes them).  Four panels: the period and the
# amplitude against the branch's parameter, stable solid, unstable dashed,
# undecided dotted, the bifurcation from the global oscillation (row 0) a
# star, folds diamonds, other events (period doubling, torus, a change of
# stability) triangles; the orbit's psi(x, t) over two periods; its
# multipliers in the complex plane with the unit circle.
load plotdir.'/common.gp'
f = word(files, 1)
st = nfiles >= 2 ? word(files, 2) : ''
mu = nfiles >= 3 ? word(files, 3) : ''
if (!exists("param") || param eq '') param = 'nu'
set multiplot layout 2, 2 title titled('Period-doubled orbits', f, 'gamma c S')
set key bottom left box opaque font ',9'
set xlabel param
v(s) = strcol('verdict') eq s
ev = "strcol('events') ne '-' && strcol('kind') eq 'orbit'"
set ylabel 'period P'
set offsets graph 0.03, graph 0.03, graph 0.06, graph 0.06
# the whole branch thin and grey underneath: its verdicts' segments join up
plot f using param:'period' with lines lw 0.5 lc rgb '#aaaaaa' notitle, \
     f using param:(v('stable') ? column('period') : NaN) with lines lw 2 lc rgb '#1f77b4' title 'stable', \
     f using param:(v('unstable') ? column('period') : NaN) with lines lw 2 dt 2 lc rgb '#d62728' title 'unstable', \
     f using param:(v('undecided') || v('none') ? column('period') : NaN) with lines lw 2 dt 3 lc rgb '#7f7f7f' title 'undecided', \
     f using param:(strcol('kind') eq 'bifurcation' ? column('period') : NaN) with points pt 3 ps 2.5 lc rgb '#000000' title 'bifurcation (period 2T)', \
     f using param:(strcol('kind') eq 'fold' ? column('period') : NaN) with points pt 13 ps 1.8 lc rgb '#ff7f0e' title 'fold', \
     f using param:(@ev ? column('period') : NaN) with points pt 9 ps 1.8 lc rgb '#9467bd' title 'event'
set ylabel 'amplitude, max_t (max_x {/Symbol y} - min_x {/Symbol y})'
set key off
plot f using param:'amplitude' with lines lw 0.5 lc rgb '#aaaaaa' notitle, \
     f using param:(v('stable') ? column('amplitude') : NaN) with lines lw 2 lc rgb '#1f77b4' notitle, \
     f using param:(v('unstable') ? column('amplitude') : NaN) with lines lw 2 dt 2 lc rgb '#d62728' notitle, \
     f using param:(v('undecided') || v('none') ? column('amplitude') : NaN) with lines lw 2 dt 3 lc rgb '#7f7f7f' notitle, \
     f using param:(strcol('kind') eq 'bifurcation' ? column('amplitude') : NaN) with points pt 3 ps 2.5 lc rgb '#000000' notitle, \
     f using param:(strcol('kind') eq 'fold' ? column('amplitude') : NaN) with points pt 13 ps 1.8 lc rgb '#ff7f0e' notitle, \
     f using param:(@ev ? column('amplitude') : NaN) with points pt 9 ps 1.8 lc rgb '#9467bd' notitle
if (st ne '') {
    set datafile separator whitespace
    set xlabel 'position x'
    set ylabel 'time t (two periods)'
    set cblabel '{/Symbol y}'
    set palette defined (0 '#08306b', 1 '#2171b5', 2 '#6baed6', 3 '#f7fbff', 4 '#fdae6b', 5 '#d94801', 6 '#7f2704')
    stats st nonuniform matrix using 3 nooutput name 'PSI'
    psimax = abs(PSI_min) > abs(PSI_max) ? abs(PSI_min) : abs(PSI_max)
    set cbrange [-psimax : psimax]
    set offsets 0, 0, 0, 0
    set autoscale xfix
    set autoscale yfix
    set title 'the orbit nearest --at' font ',10'
    plot st nonuniform matrix using 1:2:3 with image
    set datafile separator tab
    set title ''
    unset cblabel
    set autoscale x
    set autoscale y
}
if (mu ne '') {
    set xlabel 'Re m'
    set ylabel 'Im m'
    set size ratio -1
    set key top left box opaque font ',9'
    set parametric
    set trange [0:2*pi]
    set xrange [-1.6:1.6]
    set yrange [-1.3:1.3]
    k(s) = strcol('kind') eq s
    plot cos(t), sin(t) with lines lc rgb '#888888' title 'unit circle', \
         mu using 're':(k('physical') ? column('im') : NaN) with points pt 7 ps 1.3 lc rgb '#1f77b4' title 'multiplier', \
         mu using 're':(k('trivial_time') || k('trivial_space') ? column('im') : NaN) with points pt 6 ps 1.5 lc rgb '#2ca02c' title 'trivial (symmetry)', \
         mu using 're':(k('grid') ? column('im') : NaN) with points pt 2 ps 1.3 lc rgb '#7f7f7f' title 'grid mode'
    unset parametric
    set size noratio
}
unset multiplot
