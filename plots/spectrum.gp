# The ring spectrum of front trains in the complex plane: Re sigma on x,
# Im sigma on y, each eigenvalue colored by its Bloch index j (kappa =
# 2 pi j / S), the translation mode circled; one panel per data file (data:
# bkfront stability, e.g. an unstable and a stable train side by side).
load plotdir.'/common.gp'
if (!exists("minwidth")) minwidth = 450 * nfiles
if (width < minwidth) width = minwidth
set xlabel 'Re {/Symbol s}'
set ylabel 'Im {/Symbol s}'
set key bottom left
set palette defined (0 '#1f77b4', 1 '#2ca02c', 2 '#ff7f0e', 3 '#d62728', 4 '#9467bd')
set cblabel 'Bloch index j'
# Re sigma = 0, the stability boundary, always in view
set xrange [*<0:0<*]
set offsets graph 0.05, graph 0.05, 0, 0
set xzeroaxis lc rgb '#999999'
set arrow from 0, graph 0 to 0, graph 1 nohead lc rgb '#777777' dt 2
# The first comment lines name the root: "# root: n N, ..." and the verdict.
nfronts(f) = system(sprintf("sed -n 's/^# root: n \\([0-9]*\\),.*/\\1/p' '%s'", f))
verdict(f) = system(sprintf("sed -n 's/^# stable: \\([a-z]*\\);.*/\\1/p' '%s'", f))
if (nfiles > 1) set multiplot layout 1, nfiles title (title ne '' ? title : \
  sprintf('Spectra of front trains on the ring:  {/Symbol g} = %g,  c = %g,  {/Symbol n} = %g,  S = %g', gamma, c, nu, S))
do for [i = 1:nfiles] {
    f = word(files, i)
    set title sprintf('n = %s (stable: %s)', nfronts(f), verdict(f))
    if (nfiles == 1 && title ne '') { set title title }
    plot f using 're':'im':'j' with points pt 7 ps 1.1 lc palette notitle, \
         f using 're':(column('translation') > 0 ? column('im') : NaN) \
           with points pt 6 ps 2.2 lc rgb '#000000' title 'translation ({/Symbol s} = 0)'
}
if (nfiles > 1) unset multiplot
