# The inputs a table was computed at, as gnuplot enhanced text: for each
# name of `names` (space-separated) that the table's "# command:" comment
# line gives as --NAME VALUE, "NAME = VALUE", joined by commas.  Every
# bkfront table carries that line, so a figure states what it shows without
# being told (common.gp: inputs(f, names)).
# With raw=1, the value of the first name alone (empty when not given).
#     awk -v names='gamma c nu S' -f inputs.awk TABLE
function sym(s) {
    return s == "gamma" ? "{/Symbol g}" : s == "nu" ? "{/Symbol n}" : s == "mu" ? "{/Symbol m}" : s
}
/^# command: / {
    for (i = 3; i < NF; i++) if ($i ~ /^--/) val[substr($i, 3)] = $(i + 1)
    exit
}
!/^#/ { exit }
END {
    n = split(names, w, " ")
    if (raw) { if ((w[1] in val) && val[w[1]] !~ /^--/) printf "%s", val[w[1]]; exit }
    out = ""
    for (k = 1; k <= n; k++)
        if ((w[k] in val) && val[w[k]] !~ /^--/)
            out = out (out == "" ? "" : ",  ") sym(w[k]) " = " val[w[k]]
    printf "%s", out
}
