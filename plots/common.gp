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
