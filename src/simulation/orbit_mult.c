/* Floquet multipliers of a solved orbit: Arnoldi (ARPACK's dnaupd/dneupd,
 * reverse communication) on the monodromy's action
 * v -> R_s^{-1} DPhi_T(u0) v on the full domain, one Bloch sector at a
 * time.  The trivial eigenvectors f(u0) and d_x u0 are known: their
 * multipliers are measured on their span (W^T A W) and the span is
 * projected out of the operator in sector 0, A (I - W W^T), which keeps
 * every other multiplier exactly (W spans an invariant subspace of A) and
 * leaves none of them to be mistaken for a trivial one. */
#include "orbit_internal.h"

#include <arpack/arpack.h>
#include <gsl/gsl_math.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Multipliers below this in modulus are the projections' null space (or
 * too small to matter for stability), not reported. */
#define MULT_FLOOR 1e-10

typedef struct {
    bkf_orbit *ob;
    orbit_flow *fl;
    size_t N, n, m, Nc;       /* n = 2N */
    double T, s, tol;
    const double *u;
    double *w[2];             /* orthonormal trivial directions */
    size_t ntriv;
    double *tmp, *tmp2;
    int sector;               /* the sector projected on, -1: none */
    size_t matvecs;
    const double *start;      /* Arnoldi's start (n values), NULL: pseudo-random */
    double *startbuf;         /* n values for it */
    double *top, top_abs;     /* the largest physical multiplier's eigenvector (real part) */
    int top_sector;
    double *save;             /* the converged Ritz vectors' sum goes here, or NULL */
    int probe;                /* no Ritz residuals (only the value is wanted) */
    double *mem;
    bkf_error err;
} mult_op;

static double dot(const double *a, const double *b, size_t n)
{
    double s = 0.0;
    for (size_t i = 0; i < n; i++) s += a[i] * b[i];
    return s;
}

/* The real sector {j, m - j}: v's part that the cell shift multiplies by
 * exp(+-2 pi i j/m), in place. */
static void project_sector(mult_op *op, double *v)
{
    size_t m = op->m, Nc = op->Nc, N = op->N;
    if (m == 1 || op->sector < 0) return;
    int j = op->sector;
    double c = (j == 0 || 2 * (size_t)j == m) ? 1.0 : 2.0;
    for (int f = 0; f < 2; f++) {
        double *x = v + (size_t)f * N;
        for (size_t i = 0; i < Nc; i++) {
            for (size_t l = 0; l < m; l++) {
                double a = 0.0;
                for (size_t l2 = 0; l2 < m; l2++)
                    a += cos(2.0 * M_PI * (double)j * (double)((l2 + m - l) % m) / (double)m) *
                         x[i + l2 * Nc];
                op->tmp2[l] = c * a / (double)m;
            }
            for (size_t l = 0; l < m; l++) x[i + l * Nc] = op->tmp2[l];
        }
    }
}

/* y = R_s^{-1} DPhi_T x at flow tolerance tol. */
static int monodromy(mult_op *op, const double *x, double *y, double tol)
{
    int s = orbit_flow_run(op->fl, op->u, x, op->T, tol, NULL, y, NULL, &op->err);
    if (s) return s;
    orbit_flow_shift(op->fl, y, -op->s, y, NULL);
    op->matvecs++;
    return BKF_OK;
}

/* The operator Arnoldi sees: P A (I - W W^T) P in sector 0, P A P else. */
static int apply(mult_op *op, const double *x, double *y, double tol)
{
    size_t n = op->n;
    memcpy(op->tmp, x, n * sizeof *x);
    project_sector(op, op->tmp);
    if (op->sector <= 0)
        for (size_t k = 0; k < op->ntriv; k++) {
            double a = dot(op->w[k], op->tmp, n);
            for (size_t i = 0; i < n; i++) op->tmp[i] -= a * op->w[k][i];
        }
    int s = monodromy(op, op->tmp, y, tol);
    if (s) return s;
    project_sector(op, y);
    return BKF_OK;
}

static int push(bkf_orbit *ob, const bkf_orbit_multiplier *mu)
{
    if (ob->nmult == ob->capmult) {
        size_t cap = ob->capmult ? 2 * ob->capmult : 32;
        bkf_orbit_multiplier *p = realloc(ob->mult, cap * sizeof *p);
        if (!p) return BKF_ENOMEM;
        ob->mult = p;
        ob->capmult = cap;
    }
    ob->mult[ob->nmult++] = *mu;
    return BKF_OK;
}

/* The grid-scale content of an eigenvector: the larger tail of its two
 * fields (and of the real and imaginary parts). */
static double tail_of(mult_op *op, const double *zr, const double *zi)
{
    bkf_pde *pde = op->fl->pde;
    double t = 0.0;
    for (int f = 0; f < 2; f++) {
        t = fmax(t, bkf_pde_spectral_tail(pde, zr + (size_t)f * op->N));
        if (zi) t = fmax(t, bkf_pde_spectral_tail(pde, zi + (size_t)f * op->N));
    }
    return t;
}

/* The trivial multipliers: the eigenvalues of W^T A W (one or two), each
 * with the residual |A W - W (W^T A W)| as its error. */
static int trivial(mult_op *op, bkf_orbit_spectrum *sp, double orbit_err, bkf_error *err)
{
    size_t n = op->n, k = op->ntriv;
    double M[2][2] = {{0, 0}, {0, 0}}, res = 0.0;
    double *Aw[2];
    double *buf = malloc(2 * n * sizeof *buf);
    if (!buf) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    Aw[0] = buf;
    Aw[1] = buf + n;
    for (size_t a = 0; a < k; a++) {
        int s = monodromy(op, op->w[a], Aw[a], op->tol);
        if (s) {
            free(buf);
            return bkf_error_set(err, s, "%s", op->err.message);
        }
        for (size_t b = 0; b < k; b++) M[b][a] = dot(op->w[b], Aw[a], n);
    }
    for (size_t a = 0; a < k; a++) {
        double r = 0.0;
        for (size_t i = 0; i < n; i++) {
            double v = Aw[a][i];
            for (size_t b = 0; b < k; b++) v -= op->w[b][i] * M[b][a];
            r += v * v;
        }
        res = fmax(res, sqrt(r));
    }
    free(buf);
    double lam[2][2]; /* re, im */
    if (k == 1) {
        lam[0][0] = M[0][0];
        lam[0][1] = 0.0;
    } else {
        double tr = M[0][0] + M[1][1], det = M[0][0] * M[1][1] - M[0][1] * M[1][0];
        double disc = tr * tr / 4 - det;
        double sq = sqrt(fabs(disc));
        lam[0][0] = tr / 2 + (disc >= 0 ? sq : 0);
        lam[1][0] = tr / 2 - (disc >= 0 ? sq : 0);
        lam[0][1] = disc >= 0 ? 0 : sq;
        lam[1][1] = disc >= 0 ? 0 : -sq;
    }
    sp->trivial_found = 0;
    sp->trivial_dev = 0.0;
    for (size_t a = 0; a < k; a++) {
        bkf_orbit_multiplier mu;
        memset(&mu, 0, sizeof mu);
        mu.re = lam[a][0];
        mu.im = lam[a][1];
        mu.abs = hypot(mu.re, mu.im);
        mu.err = res + orbit_err;
        mu.kind = a == 0 ? BKF_ORBIT_MULT_TRIVIAL_TIME : BKF_ORBIT_MULT_TRIVIAL_SPACE;
        mu.alignment = 1.0;
        double dev = hypot(mu.re - 1.0, mu.im);
        sp->trivial_dev = fmax(sp->trivial_dev, dev);
        /* found: 1 within its error, and the span invariant to that error */
        if (dev <= fmax(10.0 * mu.err, 1e-6)) sp->trivial_found++;
        if (push(op->ob, &mu)) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    return BKF_OK;
}

static int by_sector_then_abs(const void *a, const void *b)
{
    const bkf_orbit_multiplier *x = a, *y = b;
    if (x->sector != y->sector) return x->sector < y->sector ? -1 : 1;
    if (x->kind != y->kind) {
        int tx = x->kind == BKF_ORBIT_MULT_TRIVIAL_TIME || x->kind == BKF_ORBIT_MULT_TRIVIAL_SPACE;
        int ty = y->kind == BKF_ORBIT_MULT_TRIVIAL_TIME || y->kind == BKF_ORBIT_MULT_TRIVIAL_SPACE;
        if (tx != ty) return tx ? -1 : 1;
    }
    return x->abs > y->abs ? -1 : x->abs < y->abs ? 1 : 0;
}

/* One Ritz pair (re, im; vector zr + i zi, zi NULL for a real one) as a
 * multiplier (and its conjugate), classified; ritz holds H's ncv Ritz
 * values (re, then im) and their estimates. */
static int record(mult_op *op, const bkf_orbit_mult_options *o, double re, double im,
                  const double *zr, const double *zi, const double *ritz, size_t ncv,
                  double orbit_err, double tangent_rel)
{
    double mag = hypot(re, im);
    /* its residual: H's estimate for it, or where no Ritz value of H
     * matches, what ARPACK's convergence test guarantees */
    double res = o->arnoldi_tol * mag, best = INFINITY;
    for (size_t q = 0; q < ncv; q++) {
        double d = hypot(ritz[q] - re, fabs(ritz[ncv + q]) - fabs(im));
        if (d < best && d <= 1e-8 * fmax(1.0, mag)) {
            best = d;
            res = ritz[2 * ncv + q];
        }
    }
    bkf_orbit_multiplier mu;
    memset(&mu, 0, sizeof mu);
    mu.re = re;
    mu.im = fabs(im);
    mu.abs = mag;
    /* twice the residual, as the orbit's flow share (orbit.c); the flow's
     * own share is added by the caller, measured once */
    mu.err = 2.0 * res + tangent_rel * mag + orbit_err;
    mu.sector = op->sector < 0 ? 0 : (size_t)op->sector;
    mu.tail = tail_of(op, zr, zi);
    mu.kind = mu.tail > o->grid_tail ? BKF_ORBIT_MULT_GRID : BKF_ORBIT_MULT_PHYSICAL;
    double al = 0.0, nz = sqrt(dot(zr, zr, op->n));
    for (size_t t = 0; t < op->ntriv; t++) al = fmax(al, fabs(dot(op->w[t], zr, op->n)) / nz);
    mu.alignment = al;
    if (!op->probe && mu.kind == BKF_ORBIT_MULT_PHYSICAL && mag > op->top_abs) {
        op->top_abs = mag;
        op->top_sector = op->sector;
        memcpy(op->top, zr, op->n * sizeof *zr);
    }
    if (push(op->ob, &mu)) return BKF_ENOMEM;
    if (im != 0.0) {
        mu.im = -mu.im;
        if (push(op->ob, &mu)) return BKF_ENOMEM;
    }
    return BKF_OK;
}

/* One sector's k leading multipliers. */
static int arnoldi(mult_op *op, const bkf_orbit_mult_options *o, double orbit_err,
                   double tangent_rel, size_t *nconv_out, size_t *nev_out, bkf_error *err)
{
    a_int n = (a_int)op->n;
    a_int nev = (a_int)o->k;
    if (nev > n - 2) nev = n - 2;
    /* Each basis vector is a tangent flow over the period: a basis of
     * 2 nev + 6 converges in one or two restarts on these monodromies
     * (fast-decaying spectra), where nev + 20 paid 20 flows up front per
     * sector (k 2: 23 flows a sector against 12 to 14; k 10: 57 against 52) */
    a_int ncv = 2 * nev + (op->start ? 2 : 6);
    if (ncv > n) ncv = n;
    a_int lworkl = 3 * ncv * ncv + 6 * ncv;
    double *resid = malloc((size_t)n * sizeof *resid);
    double *V = malloc((size_t)n * (size_t)ncv * sizeof *V);
    double *workd = malloc(3 * (size_t)n * sizeof *workd);
    double *workl = malloc((size_t)lworkl * sizeof *workl);
    double *dr = malloc((size_t)(nev + 1) * sizeof *dr);
    double *di = malloc((size_t)(nev + 1) * sizeof *di);
    double *Z = malloc((size_t)n * (size_t)(nev + 1) * sizeof *Z);
    double *workev = malloc(3 * (size_t)ncv * sizeof *workev);
    a_int *select = calloc((size_t)ncv, sizeof *select);
    double *ritz = malloc(3 * (size_t)ncv * sizeof *ritz);
    int s = BKF_OK;
    if (!resid || !V || !workd || !workl || !dr || !di || !Z || !workev || !select || !ritz) {
        s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
        goto done;
    }
    /* a given start, or a fixed pseudo-random one (reproducible), in the
     * sector */
    unsigned long long st = 0x9E3779B97F4A7C15ULL + (unsigned long long)op->sector;
    double big = 0.0;
    for (a_int i = 0; op->start && i < n; i++) big = fmax(big, fabs(op->start[i]));
    for (a_int i = 0; i < n; i++) {
        st = st * 6364136223846793005ULL + 1442695040888963407ULL;
        resid[i] = (double)(st >> 11) / 9007199254740992.0 - 0.5;
        /* a trace of the random one: a start inside an invariant subspace
         * would stop the Krylov space short of the k asked */
        if (op->start) resid[i] = op->start[i] + 1e-8 * big * resid[i];
    }
    project_sector(op, resid);
    a_int iparam[11] = {0}, ipntr[14] = {0};
    iparam[0] = 1;
    iparam[2] = o->max_restarts;
    iparam[6] = 1;
    a_int ido = 0, info = 1;
    for (;;) {
        dnaupd_c(&ido, "I", n, "LM", nev, o->arnoldi_tol, resid, ncv, V, n, iparam, ipntr, workd,
                 workl, lworkl, &info);
        if (ido != -1 && ido != 1) break;
        if ((s = apply(op, workd + ipntr[0] - 1, workd + ipntr[1] - 1, op->tol))) {
            bkf_error_set(err, s, "%s", op->err.message);
            goto done;
        }
        if (op->ob->o.progress &&
            op->ob->o.progress("arnoldi", fmin(1.0, (double)op->matvecs / (double)(4 * ncv)),
                               op->ob->o.progress_data)) {
            s = bkf_error_set(err, BKF_ECANCELED, "canceled during Arnoldi");
            goto done;
        }
    }
    if (info < 0 || (info != 0 && info != 1)) {
        s = bkf_error_set(err, BKF_ENUMERIC, "ARPACK dnaupd failed (info %d) in sector %d",
                          (int)info, op->sector);
        goto done;
    }
    /* H's Ritz values and their estimates |f| |e_k^T y|, the residual of
     * each unit Ritz vector in the operator Arnoldi saw (dneupd reuses
     * workl) */
    memcpy(ritz, workl + ipntr[5] - 1, (size_t)ncv * sizeof *ritz);
    memcpy(ritz + ncv, workl + ipntr[6] - 1, (size_t)ncv * sizeof *ritz);
    memcpy(ritz + 2 * ncv, workl + ipntr[7] - 1, (size_t)ncv * sizeof *ritz);
    a_int nconv = iparam[4];
    *nev_out = (size_t)nev;
    *nconv_out = (size_t)nconv;
    if (nconv < 1) {
        s = bkf_error_set(err, BKF_ENUMERIC,
                          "ARPACK converged no multiplier in sector %d after %d restarts",
                          op->sector, o->max_restarts);
        goto done;
    }
    a_int info2 = 0;
    dneupd_c(1, "A", select, dr, di, Z, n, 0.0, 0.0, workev, "I", n, "LM", nev, o->arnoldi_tol,
             resid, ncv, V, n, iparam, ipntr, workd, workl, lworkl, &info2);
    if (info2 != 0) {
        s = bkf_error_set(err, BKF_ENUMERIC, "ARPACK dneupd failed (info %d) in sector %d",
                          (int)info2, op->sector);
        goto done;
    }
    nconv = iparam[4];
    *nconv_out = (size_t)nconv;
    if (op->save) {
        memset(op->save, 0, (size_t)n * sizeof *op->save);
        for (a_int k = 0; k < nconv; k++) {
            const double *z = Z + (size_t)k * (size_t)n;
            double nz = sqrt(dot(z, z, op->n));
            for (size_t i = 0; nz > 0 && i < op->n; i++) op->save[i] += z[i] / nz;
        }
    }
    for (a_int k = 0; k < nconv; k++) {
        double re = dr[k], im = di[k];
        int pair = im != 0.0;
        if (pair && im < 0) continue; /* its conjugate carries the vector */
        const double *zr = Z + (size_t)k * (size_t)n;
        const double *zi = pair && k + 1 < nconv ? Z + (size_t)(k + 1) * (size_t)n : NULL;
        if (pair && !zi) continue;
        if (!(hypot(re, im) >= MULT_FLOOR)) continue;
        if (record(op, o, re, im, zr, zi, ritz, (size_t)ncv, orbit_err, tangent_rel)) {
            s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
            goto done;
        }
    }
done:
    free(resid);
    free(V);
    free(workd);
    free(workl);
    free(dr);
    free(di);
    free(Z);
    free(workev);
    free(select);
    free(ritz);
    return s;
}

/* The operator about the state u (2N values on fl's full domain) of period
 * T and shift sh, with its trivial directions f(u) and, for a generic
 * continuum orbit, d_x u. */
static int op_init(mult_op *op, bkf_orbit *ob, orbit_flow *fl, const double *u, double T,
                   double sh, size_t Nc, double tol, bkf_error *err)
{
    memset(op, 0, sizeof *op);
    op->ob = ob;
    op->fl = fl;
    op->N = fl->N;
    op->n = 2 * op->N;
    op->m = ob->cells;
    op->Nc = Nc;
    op->T = T;
    op->s = sh;
    op->tol = tol;
    op->u = u;
    op->sector = -1;
    size_t n = op->n;
    op->mem = malloc((6 * n + op->m) * sizeof *op->mem);
    if (!op->mem) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    op->w[0] = op->mem;
    op->w[1] = op->mem + n;
    op->tmp = op->mem + 2 * n;
    op->startbuf = op->mem + 3 * n;
    op->top = op->mem + 4 * n;
    op->top_abs = -1.0;
    op->tmp2 = op->mem + 5 * n; /* m values for the sector sums, then scratch */
    int s = orbit_flow_rhs(fl, u, op->w[0], err);
    if (s) return s;
    double nf = sqrt(dot(op->w[0], op->w[0], n));
    for (size_t i = 0; i < n; i++) op->w[0][i] /= nf;
    op->ntriv = 1;
    if (ob->model.kind == BKF_MODEL_CONTINUUM && ob->result.symmetry == BKF_ORBIT_SYM_GENERIC) {
        orbit_flow_dx(fl, u, op->w[1]);
        double a = dot(op->w[0], op->w[1], n);
        for (size_t i = 0; i < n; i++) op->w[1][i] -= a * op->w[0][i];
        double nd = sqrt(dot(op->w[1], op->w[1], n));
        for (size_t i = 0; i < n; i++) op->w[1][i] /= nd;
        op->ntriv = 2;
    }
    return BKF_OK;
}

/* The largest physical |m| of one sector about the orbit on its second
 * grid (NaN if Arnoldi finds none there). */
static int second_grid(bkf_orbit *ob, const bkf_orbit_mult_options *o, int sector,
                       const double *start, double *largest, size_t *matvecs, bkf_error *err)
{
    const bkf_orbit_result *r = &ob->result;
    size_t m = ob->cells, Nc2 = ob->Nc2, N2 = m * Nc2;
    bkf_model_params m2 = ob->model;
    m2.N = N2;
    *largest = NAN;
    orbit_flow *fl = orbit_flow_alloc(&m2, &ob->o, err);
    double *u = malloc(2 * N2 * sizeof *u);
    mult_op op;
    memset(&op, 0, sizeof op);
    int s = fl && u ? BKF_OK : bkf_error_set(err, BKF_ENOMEM, "out of memory");
    if (!s) {
        for (size_t l = 0; l < m; l++) {
            memcpy(u + l * Nc2, ob->ucell2, Nc2 * sizeof *u);
            memcpy(u + N2 + l * Nc2, ob->ucell2 + Nc2, Nc2 * sizeof *u);
        }
        s = op_init(&op, ob, fl, u, r->period2, r->shift2, Nc2, o->flow_tol, err);
    }
    if (!s) {
        op.sector = m == 1 ? -1 : sector;
        op.probe = 1;
        /* one, started from its eigenvector on the first grid: it
         * converges in the first basis (if a grid mode led on the finer
         * grid the verdict would say so, undecided) */
        if ((s = orbit_flow_resample(fl, start, ob->model.N, op.startbuf, err))) goto out;
        op.start = op.startbuf;
        bkf_orbit_mult_options po = *o;
        po.k = 1;
        size_t n0 = ob->nmult, nconv = 0, nev = 0;
        s = arnoldi(&op, &po, 0.0, 0.0, &nconv, &nev, err);
        for (size_t i = n0; !s && i < ob->nmult; i++)
            if (ob->mult[i].kind == BKF_ORBIT_MULT_PHYSICAL &&
                !(ob->mult[i].abs <= *largest))
                *largest = ob->mult[i].abs;
        ob->nmult = n0;
    }
out:
    *matvecs += op.matvecs;
    free(op.mem);
    free(u);
    orbit_flow_free(fl);
    return s;
}

int orbit_mult_run(bkf_orbit *ob, const bkf_orbit_mult_options *o, bkf_orbit_spectrum *sp,
                   bkf_error *err)
{
    memset(sp, 0, sizeof *sp);
    sp->verdict = BKF_ORBIT_UNDECIDED;
    ob->nmult = 0;
    if (!ob->full) {
        bkf_error e;
        if (!(ob->full = orbit_flow_alloc(&ob->model, &ob->o, &e)))
            return bkf_error_set(err, e.status, "%s", e.message);
    }
    const bkf_orbit_result *r = &ob->result;
    mult_op op;
    int s = op_init(&op, ob, ob->full, ob->psi /* psi then eta, contiguous */, r->period,
                    r->shift, ob->Nc, o->flow_tol, err);
    if (s) goto done;
    sp->trivial_expected = op.ntriv;
    double orbit_err = r->err;
    if ((s = trivial(&op, sp, orbit_err, err))) goto done;
    int j0 = o->sector < 0 ? 0 : o->sector, j1 = o->sector < 0 ? (int)(op.m / 2) : o->sector;
    size_t short_of = 0, nsec = op.m / 2 + 1, n = op.n;
    if (!ob->warm) {
        if (!(ob->warm = malloc(nsec * n * sizeof *ob->warm))) {
            s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
            goto done;
        }
        ob->warm_sectors = 0;
    }
    const bkf_orbit *ws = o->warm_start;
    int warm = ws && ws->warm && ws->model.N == ob->model.N && ws->cells == ob->cells &&
               ws->model.kind == ob->model.kind;
    for (int j = j0; j <= j1; j++) {
        op.sector = op.m == 1 ? -1 : j;
        op.start = NULL;
        if (warm && (size_t)j < ws->warm_sectors) {
            memcpy(op.startbuf, ws->warm + (size_t)j * n, n * sizeof *op.startbuf);
            op.start = op.startbuf;
        }
        op.save = ob->warm + (size_t)j * n;
        size_t nconv = 0, nev = 0;
        if ((s = arnoldi(&op, o, orbit_err, r->tangent_rel, &nconv, &nev, err))) goto done;
        if (nconv < nev) short_of += nev - nconv;
    }
    op.save = NULL;
    op.start = NULL;
    /* sectors not computed this call hold nothing to start from */
    ob->warm_sectors = j0 == 0 && j1 == (int)(nsec - 1) ? nsec : 0;
    qsort(ob->mult, ob->nmult, sizeof *ob->mult, by_sector_then_abs);
    sp->m = ob->mult;
    sp->count = ob->nmult;
    /* the largest physical multiplier, then its sector on the second grid */
    double big = -1.0;
    size_t at = 0;
    for (size_t i = 0; i < ob->nmult; i++)
        if (ob->mult[i].kind == BKF_ORBIT_MULT_PHYSICAL && ob->mult[i].abs > big) {
            big = ob->mult[i].abs;
            at = i;
        }
    /* The flow's share of every multiplier: twice the change of A x when
     * the tangent flow is made ten times more accurate, x the largest
     * physical multiplier's eigenvector (per unit |x|; not a grid mode's,
     * whose flow is far less accurate and which no verdict rests on): one
     * pair of flows where a residual per Ritz pair took one flow each. */
    if (big >= 0 && op.top_abs >= 0) {
        size_t n = op.n;
        double *x = op.top, *y1 = op.startbuf, *y2 = malloc(n * sizeof *y2);
        if (!y2) {
            s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
            goto done;
        }
        op.sector = op.top_sector;
        double d = 0.0, nx = sqrt(dot(x, x, n));
        if ((s = apply(&op, x, y1, op.tol)) || (s = apply(&op, x, y2, 0.1 * op.tol))) {
            free(y2);
            bkf_error_set(err, s, "%s", op.err.message);
            goto done;
        }
        for (size_t i = 0; i < n; i++) d += (y1[i] - y2[i]) * (y1[i] - y2[i]);
        free(y2);
        sp->flow_dev = nx > 0 ? 2.0 * sqrt(d) / nx : 0.0;
        for (size_t i = 0; i < ob->nmult; i++) ob->mult[i].err += sp->flow_dev;
    }
    sp->grid_dev = ob->model.kind == BKF_MODEL_CHAIN ? 0.0 : NAN;
    if (big >= 0 && r->N2 > 0 && ob->ucell2) {
        double big2;
        if ((s = second_grid(ob, o, op.top_sector, op.top, &big2, &op.matvecs, err)))
            goto done;
        sp->grid_dev = fabs(big2 - big); /* NaN when N2 found none */
        for (size_t i = 0; i < ob->nmult && isfinite(sp->grid_dev); i++)
            ob->mult[i].err += sp->grid_dev;
    }
    sp->matvecs = op.matvecs;
    /* the verdict: the largest physical multiplier against 1 */
    double big_err = big >= 0 ? ob->mult[at].err : 0.0, grid_big = -1.0;
    for (size_t i = 0; i < ob->nmult; i++)
        if (ob->mult[i].kind == BKF_ORBIT_MULT_GRID)
            grid_big = fmax(grid_big, ob->mult[i].abs + ob->mult[i].err);
    sp->largest_abs = big >= 0 ? big : NAN;
    sp->largest_err = big >= 0 ? big_err : NAN;
    sp->largest_index = at;
    if (sp->trivial_found < sp->trivial_expected)
        snprintf(sp->reason, sizeof sp->reason,
                 "a trivial multiplier is not 1 within its error (max |m - 1| %.3g)",
                 sp->trivial_dev);
    else if (short_of)
        snprintf(sp->reason, sizeof sp->reason,
                 "Arnoldi converged %zu fewer multipliers than asked", short_of);
    else if (big < 0)
        snprintf(sp->reason, sizeof sp->reason, "no physical multiplier found");
    else if (r->N2 > 0 && !isfinite(sp->grid_dev))
        snprintf(sp->reason, sizeof sp->reason,
                 "the largest multiplier's sector has no physical one on the second grid N %zu",
                 r->N2);
    else if (grid_big >= 1.0 && grid_big >= big - big_err)
        snprintf(sp->reason, sizeof sp->reason,
                 "a grid-scale multiplier reaches %.6g: refine N or dealias", grid_big);
    else if (big - big_err > 1.0)
        sp->verdict = BKF_ORBIT_UNSTABLE;
    else if (big + big_err < 1.0)
        sp->verdict = BKF_ORBIT_STABLE;
    else
        snprintf(sp->reason, sizeof sp->reason,
                 "the largest |m| = %.9g is within its error %.3g of 1",
                 big, big_err);
    s = BKF_OK;
done:
    free(op.mem);
    return s;
}
