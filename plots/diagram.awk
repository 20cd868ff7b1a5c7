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
# The columns are the grid's nu (the existence rows').  At each the S axis
# splits into intervals where the stability curves of n (rows `stability`,
# each curve's points in order along it, `above` the side that is stable)
# cross it: a curve's segment between two points crosses the column when
# their nu are on either side (the same rule as the diagram's C code).  A
# column that no curve crosses takes the verdict of a `state` row of its run
# (consecutive such columns with no curve point between them), or none
# (undecided).  Between two neighbouring columns with the same number of
# intervals the intervals are joined by quadrilaterals, as the boundaries
# are drawn; otherwise each column holds its intervals to half way to its
# neighbour.

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
    kind = $2; tn = $3 + 0; m = $4 + 0; nu = $5 + 0; S = $6 + 0; above = $8 + 0; cv = $1 + 0
    if (kind == "existence" && !(nu in seen)) { seen[nu] = 1; nus[++nnu] = nu }
    if (kind == "existence" && tn == n) exist[nu] = S
    else if (kind == "stability" && tn == n) {
        if (!(cv in cnpts)) curves[++ncurves] = cv
        k = ++cnpts[cv]; pnu[cv, k] = nu; pS[cv, k] = S; pa[cv, k] = above
    } else if (kind == "state" && tn == n) state[nu] = above
    else if (kind == "long_wave") lw[nu] = S
    else if (kind == "period_doubling" || kind == "other") {
        if (above) pdhi[nu, m] = S; else pdlo[nu, m] = S
        if (m > mmax) mmax = m
    }
}
# the crossings of every curve of n with the column nu = x, into cs[x, .]
function crossings(x,    c, cv, k, a, b, t, j) {
    ncross[x] = 0
    for (c = 1; c <= ncurves; c++) {
        cv = curves[c]
        if (cnpts[cv] == 1 && pnu[cv, 1] == x) {
            k = ++ncross[x]; cs[x, k] = pS[cv, 1]; ca[x, k] = pa[cv, 1]
        }
        for (k = 1; k < cnpts[cv]; k++) {
            a = pnu[cv, k]; b = pnu[cv, k + 1]
            if (!((a <= x && x < b) || (b < x && x <= a) || (k + 1 == cnpts[cv] && b == x)))
                continue
            t = b == a ? 0 : (x - a) / (b - a)
            j = ++ncross[x]
            cs[x, j] = pS[cv, k] + t * (pS[cv, k + 1] - pS[cv, k])
            ca[x, j] = t < 0.5 ? pa[cv, k] : pa[cv, k + 1]
        }
    }
}
# a curve of n has a point strictly between nu a and b
function between(a, b,    c, cv, k, lo, hi) {
    lo = a < b ? a : b; hi = a < b ? b : a
    for (c = 1; c <= ncurves; c++) {
        cv = curves[c]
        for (k = 1; k <= cnpts[cv]; k++) if (pnu[cv, k] > lo && pnu[cv, k] < hi) return 1
    }
    return 0
}
END {
    # the grid in nu, ascending
    for (i = 1; i <= nnu; i++)
        for (j = i + 1; j <= nnu; j++)
            if (nus[j] < nus[i]) { t = nus[i]; nus[i] = nus[j]; nus[j] = t }
    # the verdict of each column no curve crosses: its run's state row
    for (i = 1; i <= nnu; i++) {
        nu = nus[i]
        if (want != "oscillation") crossings(nu)
    }
    if (want != "oscillation") {
        for (i = 1; i <= nnu; i++) {
            nu = nus[i]
            # as the C code's runs: columns whose scan window is not empty
            free = (nu in exist) && (1.05 * exist[nu] > s_from ? 1.05 * exist[nu] : s_from) < s_to \
                && ncross[nu] == 0
            if (open && (!free || between(nus[last], nu))) {
                for (j = first; j <= last; j++) runstate[nus[j]] = rs
                open = 0
            }
            if (free && !open) { open = 1; first = i; rs = "" }
            if (free) {
                last = i
                if (nu in state) rs = state[nu] ? "stable" : "unstable"
            }
        }
        if (open) for (j = first; j <= last; j++) runstate[nus[j]] = rs
    }
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
            verdict = (nu in state) ? (state[nu] ? "stable" : "unstable") : \
                (runstate[nu] != "" ? runstate[nu] : "undecided")
            if (verdict == want) add(i, lo, s_to)
            continue
        }
        if (want == "undecided") continue
        from = lo
        for (a = 1; a <= c + 1; a++) {
            to = a <= c ? cs[nu, a] : s_to
            if (to < lo) continue
            # below crossing a the side it calls unstable when above = 1
            st = a <= c ? !ca[nu, a] : ca[nu, c]
            if ((st ? "stable" : "unstable") == want && to > from) add(i, from, to < s_to ? to : s_to)
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
