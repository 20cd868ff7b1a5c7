# A regime map (a scene's [sweep], bkfront sweep over nu and gamma): left,
# the regime of every run, one mark per initial state and seed around its
# grid point (states side by side, seeds one above the other); right, the
# fronts at the end of each run.  files: the sweep's table, then (with the
# sweep's thresholds key) one table of bkfront floquet --diagram per gamma,
# whose gamma is the same word of values ("map g1 g2 ..."): the global
# oscillation's period-doubling (dashed) and long-wave (solid) boundaries,
# drawn over both panels.
minwidth = 1400
load plotdir.'/common.gp'
f = word(files, 1)
regime(s) = (s eq 'continuous_slip' ? 0 : s eq 'global_oscillation' ? 1 : \
             s eq 'period_doubled_pacemakers' ? 2 : s eq 'propagating_fronts' ? 3 : \
             s eq 'irregular' ? 4 : s eq 'transient' ? 5 : 6)
colour(r) = (r == 0 ? 0x7f7f7f : r == 1 ? 0x1f77b4 : r == 2 ? 0xff7f0e : r == 3 ? 0x2ca02c : \
             r == 4 ? 0xd62728 : r == 5 ? 0x9467bd : 0x000000)
stats f using 'nu' nooutput name 'NU'
stats f using 'gamma' nooutput name 'G'
stats f using 'seed' nooutput name 'SEED'
stats f using 11 nooutput name 'FR'
fmax = FR_max >= 1 ? int(FR_max) : 1
# the initial states, in the order of the table (at most 4 told apart)
stats f using 'point' nooutput name 'P'
# the grid's spacing: mark offsets stay inside one cell
dnu = (NU_max > NU_min ? (NU_max - NU_min) / 12.0 : 0.01)
dg = (G_max > G_min ? (G_max - G_min) / 12.0 : 0.1)
nseed = SEED_max - SEED_min + 1
xoff(s) = (strstrt(s, 'oscillation') > 0 ? 0.5 : -0.5) * dnu
yoff(k) = (nseed > 1 ? (k - SEED_min) / (nseed - 1.0) - 0.5 : 0) * dg
# the boundaries of every gamma, one table per kind: nu, gamma and the
# branch, which a curve follows from gamma to gamma: the side of the
# boundary where the oscillation is stable (the interval above it, stable
# or not) and the sign of nu.  Joined in file order, two boundaries of one
# kind at one gamma made a segment between them (long wave at gamma 1.875:
# -0.916, where it becomes stable, and -0.829, where it stops being).
$PD << EOD
EOD
$LW << EOD
EOD
branch(s, nu) = (s eq 'stable' ? 1 : 0) + (nu > 0 ? 2 : 0)
# a boundary is drawn where the map is: points past its nu range left out
inmap(nu, g) = nu >= NU_min - 1.5 * dnu && nu <= NU_max + 1.5 * dnu && \
               g >= G_min - 1.5 * dg && g <= G_max + 1.5 * dg
if (nfiles > 1) {
    set table $PD
    plot for [i = 2:nfiles] word(files, i) \
        using 'nu_from':(real(word(values, i))):(branch(strcol('stability'), column('nu_from'))) \
        with table if (strcol('from_kind') eq 'period_doubling' && inmap(column('nu_from'), real(word(values, i))))
    set table $LW
    plot for [i = 2:nfiles] word(files, i) \
        using 'nu_from':(real(word(values, i))):(branch(strcol('stability'), column('nu_from'))) \
        with table if (strcol('from_kind') eq 'long_wave' && inmap(column('nu_from'), real(word(values, i))))
    unset table
}
# a table that drew no row is no datablock at all (no boundary at any
# gamma: the oscillation stable or unstable throughout): made empty here
set print $PD append
print ''
set print $LW append
print ''
unset print
# one curve per branch: a point of another branch is undefined, which
# breaks the line instead of joining across it
on(b) = (column(3) == b ? column(2) : NaN)
set xrange [NU_min - 1.5 * dnu : NU_max + 1.5 * dnu]
set yrange [G_min - 1.5 * dg : G_max + 1.5 * dg]
set xlabel '{/Symbol n}'
set ylabel '{/Symbol g}'
# no box: gnuplot lays a key below over the x label (and an empty one is then
# invisible)
set key outside below center horizontal font ',9' nobox noopaque
set multiplot layout 1, 2 title (title ne '' ? title : 'Regimes from an arbitrary initial state (left of each point: noise; right: oscillation)')
set title 'regime'
plot f using ($6 + xoff(strcol(2))):($4 + yoff($3)):(colour(regime(strcol(10)))) \
        with points pt 5 ps 1.2 lc rgb variable notitle, \
     for [r = 0:6] NaN with points pt 5 ps 1.2 lc rgb colour(r) \
        title word('continuous\_slip global\_oscillation pacemakers propagating\_fronts irregular transient failed', r + 1), \
     for [b = 0:3] $PD using 1:(on(b)) with linespoints lw 2 dt 2 pt 7 ps 0.5 lc rgb '#000000' \
        title (b == 0 ? 'period doubling (Floquet)' : ''), \
     for [b = 0:3] $LW using 1:(on(b)) with linespoints lw 2 pt 7 ps 0.5 lc rgb '#000000' \
        title (b == 0 ? 'long wave (Floquet)' : '')
set title 'fronts at the end of the run'
# a count: one colour per number of fronts, the bar's ticks at the integers
set cbrange [-0.5 : fmax + 0.5]
if (fmax < 12) { set cbtics 1 }
set cblabel 'fronts'
set palette rgb 33,13,10
set palette maxcolors fmax + 1
plot f using ($6 + xoff(strcol(2))):($4 + yoff($3)):11 with points pt 5 ps 1.2 lc palette notitle, \
     for [b = 0:3] $PD using 1:(on(b)) with linespoints lw 2 dt 2 pt 7 ps 0.5 lc rgb '#000000' \
        title (b == 0 ? 'period doubling (Floquet)' : ''), \
     for [b = 0:3] $LW using 1:(on(b)) with linespoints lw 2 pt 7 ps 0.5 lc rgb '#000000' \
        title (b == 0 ? 'long wave (Floquet)' : '')
unset multiplot
