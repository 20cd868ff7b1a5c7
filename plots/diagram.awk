# The filled regions of the (nu, S) diagram (diagram.gp) from the table of
# bkfront stability --diagram, as polygons for gnuplot's filledcurves
# closed (one polygon a block, blocks apart by a blank line):
#     awk -v n=N -v want=stable|unstable|undecided -f diagram.awk TABLE
#     awk -v want=oscillation -f diagram.awk TABLE
# n > 0: where train n is stable, unstable, or of unknown stability, over S
# from its existence boundary to the scan's top; want=oscillation: where
# the global oscillation is unstable (long wave above its curve, each
# period-doubling tongue between its edges).
#
# At each nu of the grid the S axis splits into intervals at the crossings
# (rows `stability`, `above` the side that is stable); a nu without any
# takes the verdict of its `state` row, or none (undecided).  Between two
# neighbouring nu with the same number of intervals the intervals are joined
# by quadrilaterals, as the boundaries are drawn; otherwise each nu holds
# its intervals to half way to its neighbour.
function add(col, lo, hi,    k) {
    k = ++cnt[col]
    ilo[col, k] = lo
    ihi[col, k] = hi
}
BEGIN { FS = "\t" }
/^# command: / {
    nf = split($0, w, " ")
    for (i = 1; i < nf; i++) {
        if (w[i] == "--S") s_from = w[i + 1] + 0
        if (w[i] == "--S-to") s_to = w[i + 1] + 0
    }
}
/^#/ || $1 == "curve" || NF < 8 { next }
{
    kind = $2; tn = $3 + 0; m = $4 + 0; nu = $5 + 0; S = $6 + 0; above = $8 + 0
    if (!(nu in seen)) { seen[nu] = 1; nus[++nnu] = nu }
    if (kind == "existence" && tn == n) exist[nu] = S
    else if (kind == "stability" && tn == n) {
        k = ++ncross[nu]; cs[nu, k] = S; ca[nu, k] = above
    } else if (kind == "state" && tn == n) state[nu] = above
    else if (kind == "long_wave") lw[nu] = S
    else if (kind == "period_doubling" || kind == "other") {
        if (above) pdhi[nu, m] = S; else pdlo[nu, m] = S
        if (m > mmax) mmax = m
    }
}
END {
    # the grid in nu, ascending
    for (i = 1; i <= nnu; i++)
        for (j = i + 1; j <= nnu; j++)
            if (nus[j] < nus[i]) { t = nus[i]; nus[i] = nus[j]; nus[j] = t }
    for (i = 1; i <= nnu; i++) {
        nu = nus[i]
        if (want == "oscillation") {
            if (nu in lw) add(i, lw[nu], s_to)
            for (mm = 1; mm <= mmax; mm++)
                if (((nu, mm) in pdlo) && ((nu, mm) in pdhi))
                    add(i, pdlo[nu, mm], pdhi[nu, mm] < s_to ? pdhi[nu, mm] : s_to)
            continue
        }
        if (!(nu in exist)) continue
        lo = exist[nu] > s_from ? exist[nu] : s_from
        if (lo >= s_to) continue
        c = ncross[nu] + 0
        # the crossings in S, ascending
        for (a = 1; a <= c; a++)
            for (b = a + 1; b <= c; b++)
                if (cs[nu, b] < cs[nu, a]) {
                    t = cs[nu, a]; cs[nu, a] = cs[nu, b]; cs[nu, b] = t
                    t = ca[nu, a]; ca[nu, a] = ca[nu, b]; ca[nu, b] = t
                }
        if (c == 0) {
            verdict = (nu in state) ? (state[nu] ? "stable" : "unstable") : "undecided"
            if (verdict == want) add(i, lo, s_to)
            continue
        }
        if (want == "undecided") continue
        from = lo
        for (a = 1; a <= c + 1; a++) {
            to = a <= c ? cs[nu, a] : s_to
            # below crossing a the side it calls unstable when above = 1
            st = a <= c ? !ca[nu, a] : ca[nu, c]
            if ((st ? "stable" : "unstable") == want && to > from) add(i, from, to)
            from = to
        }
    }
    for (i = 1; i <= nnu; i++) {
        left = i > 1 ? 0.5 * (nus[i - 1] + nus[i]) : nus[i]
        right = i < nnu ? 0.5 * (nus[i] + nus[i + 1]) : nus[i]
        # a lone nu (no neighbour joins it) keeps a visible width
        if (nnu == 1) { left = nus[i] - 0.005; right = nus[i] + 0.005 }
        joinl = i > 1 && cnt[i - 1] + 0 == cnt[i] + 0
        joinr = i < nnu && cnt[i + 1] + 0 == cnt[i] + 0
        for (k = 1; k <= cnt[i]; k++) {
            if (!joinl && left < nus[i]) box(left, nus[i], ilo[i, k], ihi[i, k])
            if (!joinr && right > nus[i]) box(nus[i], right, ilo[i, k], ihi[i, k])
            if (joinr) {
                printf "%.17g\t%.17g\n%.17g\t%.17g\n%.17g\t%.17g\n%.17g\t%.17g\n%.17g\t%.17g\n\n",
                    nus[i], ilo[i, k], nus[i + 1], ilo[i + 1, k], nus[i + 1], ihi[i + 1, k],
                    nus[i], ihi[i, k], nus[i], ilo[i, k]
                printed = 1
            }
        }
    }
    # gnuplot reads no polygon from an empty stream: one point, drawn as nothing
    if (!printed) printf "%.17g\tNaN\n", nnu ? nus[1] : 0
}
function box(x0, x1, y0, y1) {
    printf "%.17g\t%.17g\n%.17g\t%.17g\n%.17g\t%.17g\n%.17g\t%.17g\n%.17g\t%.17g\n\n",
        x0, y0, x1, y0, x1, y1, x0, y1, x0, y0
    printed = 1
}
