# The (nu, S) diagram of front trains (bkfront stability --diagram): for
# each n its existence boundary (thin; trains exist above) and stability
# boundaries (thick; the "above" column says which side is stable), with
# the global oscillation's long-wave threshold (black dashed: unstable
# above) and period-doubling tongues (grey: unstable between the edges of
# each m).  Rows are grouped by the curve column.
load plotdir.'/common.gp'
f = word(files, 1)
set xlabel '{/Symbol n}'
set ylabel 'S'
set key outside below center horizontal maxrows 3 font ',9'
set xtics 0.04
set title (title ne '' ? title : sprintf('Where front trains exist and are stable:  {/Symbol g} = %g,  c = %g', gamma, c))
stats f using 'curve' nooutput
ncurves = int(STATS_max)
stats f using 'n' nooutput
nmax = int(STATS_max)
set yrange [0:*]
col(n) = n % 6 + 1
is(k) = strcol('kind') eq k
plot for [i = 1:ncurves] f using 'nu':((column('curve') == i && (is('period_doubling') || is('other'))) ? column('S') : NaN) \
        with linespoints lw 1 pt 7 ps 0.3 lc rgb '#999999' notitle, \
     for [i = 1:ncurves] f using 'nu':((column('curve') == i && is('long_wave')) ? column('S') : NaN) \
        with linespoints lw 2 dt 2 pt 7 ps 0.5 lc rgb '#000000' title (i == 1 ? 'oscillation: long wave' : ''), \
     for [n = 1:nmax] f using 'nu':((is('existence') && column('n') == n) ? column('S') : NaN) \
        with lines lw 1 lc col(n) title sprintf('n = %d exists above', n), \
     for [i = 1:ncurves] f using 'nu':((column('curve') == i && is('stability')) ? column('S') : NaN):(col(int(column('n')))) \
        with linespoints lw 3 pt 7 ps 0.6 lc variable notitle, \
     NaN with linespoints lw 3 pt 7 ps 0.6 lc rgb '#555555' title 'stability boundary (thick)', \
     NaN with linespoints lw 1 pt 7 ps 0.3 lc rgb '#999999' title 'oscillation: period doubling'

