# The ring spectrum of front trains in the complex plane: Re sigma on x,
# Im sigma on y, each eigenvalue colored by its Bloch index j (kappa =
# 2 pi j / S; one colour per j, a discrete colour bar), the translation
# mode circled; one panel per data file (data: bkfront stability, e.g. an
# unstable and a stable train side by side).
load plotdir.'/common.gp'
if (!exists("minwidth")) minwidth = 450 * nfiles
if (width < minwidth) width = minwidth
set xlabel 'Re {/Symbol s}'
set ylabel 'Im {/Symbol s}'
# no key (eigenvalues may sit in any corner): the title says what is circled
set key off
set cblabel 'Bloch index j'
set format x '%g'
set xzeroaxis lc rgb '#999999'
set arrow from 0, graph 0 to 0, graph 1 nohead lc rgb '#777777' dt 2
# The first comment lines name the root: "# root: n N, ..." and the verdict.
nfronts(f) = system(sprintf("sed -n 's/^# root: n \\([0-9]*\\),.*/\\1/p' '%s'", f))
verdict(f) = system(sprintf("sed -n 's/^# stable: \\([a-z]*\\);.*/\\1/p' '%s'", f))
if (nfiles > 1) set multiplot layout 1, nfiles \
  title titled('Spectra of front trains on the ring', word(files, 1), 'gamma c nu S'). \
        (title ne '' ? '' : "\n(circled: the translation mode, {/Symbol s} = 0)")
do for [i = 1:nfiles] {
    f = word(files, i)
    set title sprintf('n = %s (stable: %s)', nfronts(f), verdict(f))
    if (nfiles == 1) { set title titled(sprintf('n = %s (stable: %s)', nfronts(f), verdict(f)), \
                                        f, 'gamma c nu S') }
    # Re sigma = 0, the stability boundary, always in view; about four ticks
    stats f using 're' nooutput name 'RE'
    xlo = RE_min < 0 ? RE_min : 0
    xhi = RE_max > 0 ? RE_max : 0
    xw = xhi - xlo > 0 ? xhi - xlo : 1e-3
    set xrange [xlo - 0.08 * xw : xhi + 0.08 * xw]
    set xtics nicestep(xw * 1.16, 5)
    set offsets 0, 0, graph 0.05, graph 0.05
    # one colour per Bloch index j, the bar's ticks at the integers
    stats f using 'j' nooutput name 'J'
    jmax = int(J_max)
    set cbrange [-0.5 : jmax + 0.5]
    if (jmax < 12) { set cbtics 1 } else { set cbtics nicestep(jmax, 6) }
    # (a palette has two colours at least: one j is one colour twice)
    set palette maxcolors (jmax > 0 ? jmax + 1 : 2)
    pal = sprintf("0 '%s'", color(1))
    do for [k = 1:(jmax > 0 ? jmax : 1)] { pal = pal.sprintf(", %d '%s'", k, color(jmax > 0 ? k + 1 : 1)) }
    eval 'set palette defined ('.pal.')'
    plot f using 're':'im':'j' with points pt 7 ps 1.1 lc palette notitle, \
         f using 're':(column('translation') > 0 ? column('im') : NaN) \
           with points pt 6 ps 2.2 lc rgb '#000000' notitle
}
if (nfiles > 1) unset multiplot
