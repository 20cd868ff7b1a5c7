# The (nu, S) phase diagram of front trains (bkfront stability --diagram):
# one panel per n, filled where the train is stable (green), exists but is
# unstable (red: the rest of where it exists), exists with stability unknown (hatched: no crossing and
# no verdict at that nu), and does not exist (grey, below its existence
# boundary); the stability boundaries drawn as the curves the command
# followed (lines through their points, each a computed spectrum).
# A last panel shows the global oscillation: unstable (violet) above its
# long-wave threshold and inside each period-doubling tongue.  The regions
# are polygons that diagram.awk makes from the table's rows; the ranges are
# the table's (its grid in nu, its S range from the command line).
load plotdir.'/common.gp'
f = word(files, 1)
region(n, what) = sprintf("< awk -v n=%d -v want=%s -f '%s/diagram.awk' '%s'", n, what, plotdir, f)
stats f using 'n' nooutput name 'N'
nmax = int(N_max)
stats f using 'nu' nooutput name 'NU'
stats f using 'curve' nooutput name 'CURVE'
ncurves = int(CURVE_max)
Slo = real(input(f, 'S'))
Shi = real(input(f, 'S-to'))
# n panels, the oscillation's and the key's
panels = nmax + 2
cols = panels <= 4 ? panels : (ceil(sqrt(1.6 * panels)) > 4 ? ceil(sqrt(1.6 * panels)) : 4)
rows = ceil(panels / (1.0 * cols))
if (width < 330 * cols) { width = 330 * cols }
if (height < 300 * rows + 60) { height = 300 * rows + 60 }
if (fmt eq 'png') {
    set terminal pngcairo size width, height enhanced font 'DejaVu Sans,11' linewidth 1.5
} else {
    if (fmt eq 'pdf') {
        set terminal pdfcairo size width/100.0, height/100.0 enhanced font 'DejaVu Sans,8'
    } else {
        set terminal svg size width, height enhanced font 'DejaVu Sans,11' dynamic
    }
}
set output out
c_stable = '#a6dba0'
c_unstable = '#f4a582'
c_none = '#d9d9d9'
c_osc = '#b2abd2'
nuw = NU_max > NU_min ? NU_max - NU_min : 0.02
set xrange [NU_min - (NU_max > NU_min ? 0 : 0.01) : NU_max + (NU_max > NU_min ? 0 : 0.01)]
set yrange [Slo : Shi]
set xtics nicestep(nuw, 4)
set format x '%g'
set xlabel '{/Symbol n}'
set ylabel 'S'
set key off
set grid front lc rgb '#bbbbbb'
is(k) = strcol('kind') eq k
# the existence boundary of n, at the foot of the window where it is below
# (trains exist throughout)
exists_at(n) = is('existence') && column('n') == n ? \
    (column('S') > Slo ? (column('S') < Shi ? column('S') : Shi) : Slo) : NaN
# the oscillation's rows: none when it is stable throughout the window
nosc = int(system(sprintf("grep -c -E '\t(long_wave|period_doubling|other)\t' '%s'", f)))
set multiplot layout rows, cols \
  title titled('Where trains of n fronts exist and are stable', f, 'gamma c')
do for [n = 1:nmax] {
    set title sprintf('n = %d', n)
    # where the train exists, unstable but where the stable and unknown
    # regions are laid over it
    plot f using 'nu':(exists_at(n)):(Shi) \
           with filledcurves fs solid 1.0 noborder lc rgb c_unstable, \
         f using 'nu':(exists_at(n)):(Slo) \
           with filledcurves fs solid 1.0 noborder lc rgb c_none, \
         region(n, 'stable') using 1:2 with filledcurves closed fs solid 1.0 noborder \
           lc rgb c_stable, \
         region(n, 'undecided') using 1:2 with filledcurves closed fs solid 1.0 noborder \
           lc rgb '#ffffff', \
         region(n, 'undecided') using 1:2 with filledcurves closed fs pattern 4 \
           lc rgb '#777777', \
         f using 'nu':(exists_at(n)) with lines lw 2 lc rgb '#333333', \
         for [i = 1:ncurves] f using 'nu': \
           (is('stability') && column('n') == n && column('curve') == i ? column('S') : NaN) \
           with lines lw 2.5 lc rgb '#1a1a1a'
}
set title 'global oscillation'
if (nosc == 0) {
    set label 1 'stable throughout' at graph 0.5, graph 0.5 center front
}
plot region(0, 'oscillation') using 1:2 with filledcurves closed fs solid 1.0 noborder \
       lc rgb c_osc, \
     for [i = 1:ncurves] f using 'nu':(is('long_wave') && column('curve') == i ? column('S') : NaN) \
       with linespoints lw 2 dt 2 pt 7 ps 0.5 lc rgb '#000000', \
     f using 'nu':(is('period_doubling') || is('other') ? column('S') : NaN) \
       with points pt 7 ps 0.4 lc rgb '#555555'
# the key: a panel of its own
unset label 1
unset title
unset border
unset tics
unset xlabel
unset ylabel
unset grid
set key center center vertical Left reverse noopaque nobox samplen 2 spacing 1.3 font ',10'
set xrange [0:1]
set yrange [0:1]
plot NaN with filledcurves fs solid 1.0 lc rgb c_stable title 'train stable', \
     NaN with filledcurves fs solid 1.0 lc rgb c_unstable title 'train unstable', \
     NaN with filledcurves fs pattern 4 lc rgb '#777777' title 'train, stability unknown', \
     NaN with filledcurves fs solid 1.0 lc rgb c_none title 'no train (below existence)', \
     NaN with lines lw 2.5 lc rgb '#1a1a1a' title 'stability boundary', \
     NaN with filledcurves fs solid 1.0 lc rgb c_osc title 'oscillation unstable', \
     NaN with lines lw 2 dt 2 lc rgb '#000000' title 'long-wave threshold'
unset multiplot
