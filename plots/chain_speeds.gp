# The chain's front speeds beside the continuum's (data: bkfront speeds, the
# continuum's table and chain tables `--model chain --stability` for several
# N; `values` names each file: 'continuum' or the chain's blocks N).
# Left: v against n, chain waves filled where stable, open where not.
# Right: how v approaches the continuum's as the chain is refined: |v/v_c - 1|
# against blocks per unit length N/S for n = 1 .. nconv, beside the second
# order (N/S)^-2 the lattice Laplacian's -q^2 (1 - q^2 h^2/12) predicts.
minwidth = 1400
load plotdir.'/common.gp'
set multiplot layout 1, 2 title titled('The chain against the continuum', word(files, 1), 'gamma c nu S')
iscont(i) = word(values, i) eq 'continuum'
chain_title(i) = iscont(i) ? '' : sprintf('chain, N = %s', word(values, i))
set xlabel 'number of fronts n'
set ylabel 'front speed v'
set logscale y
# every table's speeds in view, the ticks from their range
vlo = 1e300
vhi = 0
do for [i=1:nfiles] {
  stats word(files, i) using 'v' nooutput
  if (exists("STATS_min")) { vlo = STATS_min < vlo ? STATS_min : vlo; vhi = STATS_max > vhi ? STATS_max : vhi }
  undefine STATS_min STATS_max
}
if (vhi < vlo) { vlo = 0.1; vhi = 1 }
vpad = (vhi / vlo)**0.06 > 1.05 ? (vhi / vlo)**0.06 : 1.05
set yrange [vlo / vpad : vhi * vpad]
call plotdir.'/logtics.gp' 'y' sprintf('%.17g', vlo / vpad) sprintf('%.17g', vhi * vpad)
set key top right
set offsets 0.5, 0.5, 0, 0
# Stability is drawn where a table has it (--stability): filled stable,
# open unstable; a chain table without it is drawn with crosses.  gnuplot's
# || does not evaluate its right side when the left one is true, so a table
# without the column is never asked for it.
header(f) = system(sprintf("grep -m1 -v '^#' '%s'", f))
array hs[nfiles]
do for [i=1:nfiles] { hs[i] = strstrt(header(word(files, i)), "stable") > 0 }
plot for [i=1:nfiles] word(files, i) using 'n':(iscont(i) ? column('v') : NaN) \
       with linespoints lw 2 pt 6 ps 1.2 lc rgb 'black' title (iscont(i) ? 'continuum' : ''), \
     for [i=1:nfiles] word(files, i) \
       using 'n':(iscont(i) || !hs[i] || strcol('stable') ne 'yes' ? NaN : column('v')) \
       with points pt 7 ps 1.1 lc rgb color(i) title (hs[i] ? chain_title(i) : ''), \
     for [i=1:nfiles] word(files, i) \
       using 'n':(iscont(i) || !hs[i] || strcol('stable') eq 'yes' ? NaN : column('v')) \
       with points pt 6 ps 1.1 lc rgb color(i) notitle, \
     for [i=1:nfiles] word(files, i) using 'n':(iscont(i) || hs[i] ? NaN : column('v')) \
       with points pt 2 ps 1.1 lc rgb color(i) title (hs[i] ? '' : chain_title(i)), \
     NaN with points pt 7 lc rgb 'black' title 'stable', \
     NaN with points pt 6 lc rgb 'black' title 'unstable'
unset offsets
# right: the fastest wave of each n (the fronts; one per n here) per table,
# gathered into a datablock: one line per chain, N/S then v for n = 1..nconv
nconv = 4
do for [i=1:nfiles] {
  if (iscont(i)) {
    stats word(files, i) using 'n' nooutput name 'NC'
    if (exists("NC_max")) { nconv = NC_max < nconv ? int(NC_max) : nconv }
  }
}
array vc[nconv]
xmax = 1
set print $conv
do for [i=1:nfiles] {
  line = iscont(i) ? '' : sprintf('%.17g', real(word(values, i)) / S)
  do for [k=1:nconv] {
    stats word(files, i) using (column('n') == k ? column('v') : NaN) nooutput
    # n beyond a table's rows: stats leaves STATS_max undefined, no point
    vk = exists("STATS_max") ? STATS_max : NaN
    if (iscont(i)) { vc[k] = vk } else { line = line.sprintf(' %.17g', vk) }
  }
  if (!iscont(i)) { print line; xmax = real(word(values, i)) / S > xmax ? real(word(values, i)) / S : xmax }
}
unset print
set datafile separator whitespace
set xlabel 'blocks per unit length N/S'
set ylabel '|v / v_{continuum} - 1|'
set logscale xy
set logscale x 2
set xtics 2
set ytics autofreq
set format y '10^{%T}'
set yrange [*:*]
set xrange [0.8:1.25 * xmax]
set key bottom left
plot for [k=1:nconv] $conv using 1:(abs(column(k + 1) / vc[k] - 1)) with linespoints lw 2 pt 7 \
       lc rgb color(k) title sprintf('n = %d', k), \
     1e-3 / x**2 with lines dt 2 lc rgb 'black' title '{/Symbol \265} (N/S)^{-2}'
unset multiplot
