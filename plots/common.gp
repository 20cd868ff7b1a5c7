# Shared by every bkfront figure script: the terminal for `fmt` writing to
# `out` at width x height pixels (PDF at 100 px per inch), and TSV input.
# bkfront run sets fmt, out, width, height, title and the data variables.
if (!exists("width")) width = 900
if (!exists("height")) height = 600
if (!exists("title")) title = ''
if (exists("minwidth")) { if (width < minwidth) { width = minwidth } }
if (fmt eq 'png') {
    set terminal pngcairo size width, height enhanced font 'DejaVu Sans,12' linewidth 1.5
} else {
    if (fmt eq 'pdf') {
        set terminal pdfcairo size width/100.0, height/100.0 enhanced font 'DejaVu Sans,9'
    } else {
        set terminal svg size width, height enhanced font 'DejaVu Sans,12' dynamic
    }
}
set output out
set datafile separator tab
set datafile commentschars '#'
set key box opaque
set grid lc rgb '#dddddd'
nfiles = words(files)
colors = '#1f77b4 #2ca02c #d62728 #9467bd #ff7f0e #8c564b #17becf #7f7f7f #bcbd22 #e377c2'
color(i) = word(colors, (int(i) - 1) % words(colors) + 1)
# The inputs table f was computed at, for the names given ('gamma c nu S'),
# from its "# command:" line (inputs.awk): every figure says what it shows.
inputs(f, names) = system(sprintf("awk -v names='%s' -f '%s/inputs.awk' '%s'", \
                                  names, plotdir, f))
# The value of one input of f ('' when its command does not give it).
input(f, name) = system(sprintf("awk -v raw=1 -v names='%s' -f '%s/inputs.awk' '%s'", \
                                name, plotdir, f))
# The figure's title: the scene's own, else `what` and the inputs of f.
titled(what, f, names) = title ne '' ? title : \
    (inputs(f, names) eq '' ? what : what.':  '.inputs(f, names))
# A data range [lo, hi] widened by a fraction `pad` of its width on each
# side (a point on the frame is hidden by it), on a log axis by a factor.
padlo(lo, hi, pad) = lo - pad * (hi > lo ? hi - lo : (lo != 0 ? abs(lo) : 1))
padhi(lo, hi, pad) = hi + pad * (hi > lo ? hi - lo : (hi != 0 ? abs(hi) : 1))
# A tick step of 1, 2 or 5 x 10^k giving about n intervals over a width w
# (gnuplot's own step crowds a narrow panel: "0.010.020.03").
nicestep(w, n) = (ns_s = (w > 0 ? w : 1) / n, ns_p = 10.0**floor(log10(ns_s)), \
    ns_s / ns_p <= 1 ? ns_p : ns_s / ns_p <= 2 ? 2 * ns_p : ns_s / ns_p <= 5 ? 5 * ns_p : 10 * ns_p)
