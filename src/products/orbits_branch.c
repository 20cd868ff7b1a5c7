/* The branch of period-doubled orbits (orbits.h): the period-doubling point
 * of the global oscillation, the switch onto the new branch, its
 * continuation and each point's polish and multipliers. */
#include "orbits_internal.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_roots.h>

#include "bkfront/continuation.h"
#include "bkfront/floquet.h"
#include "bkfront/pde.h"

/* The flow of the continuation: tight, so that forward differences of it
 * with steps 1e-6 are good to about 1e-6 (the adaptive step's choices make
 * the flow rough at the level of its tolerance), enough for Newton to gain
 * six digits an iteration. */
#define FLOW_TOL 1e-12
#define FD_STEP 1e-6
/* The Jacobian is reused while the unknowns stay this close (scaled) to
 * where it was formed: Newton's last iterations and the tangent that
 * follows them need no new one. */
#define JAC_REUSE 1e-4
/* The critical mode's amplitude (of psi's cos(q_j x)) at the first points. */
#define SWITCH_POINTS 3

const char *bkf_orbits_param_name(bkf_orbits_param p)
{
    static const char *const names[] = {"nu", "gamma", "c", "S"};
    return (unsigned)p < 4 ? names[p] : "?";
}

double orbits_param_get(const bkf_model_params *m, bkf_orbits_param p)
{
    switch (p) {
    case BKF_ORBITS_GAMMA: return m->gamma;
    case BKF_ORBITS_C: return m->c;
    case BKF_ORBITS_S: return m->S;
    default: return m->nu;
    }
}

void orbits_param_set(bkf_model_params *m, bkf_orbits_param p, double v)
{
    switch (p) {
    case BKF_ORBITS_GAMMA: m->gamma = v; break;
    case BKF_ORBITS_C: m->c = v; break;
    case BKF_ORBITS_S: m->S = v; break;
    default: m->nu = v; break;
    }
}

/* The wavenumber floquet must see for mode j: the chain's Laplacian has
 * the eigenvalue -(2/h sin(q h/2))^2 where the continuum's has -q^2. */
double orbits_q_effective(const bkf_model_params *m, size_t j, size_t N)
{
    double q = 2.0 * M_PI * (double)j / m->S;
    if (m->kind != BKF_MODEL_CHAIN) return q;
    double h = m->S / (double)N;
    return 2.0 / h * sin(q * h / 2.0);
}

typedef struct {
    bkf_floquet *fl;
    bkf_model_params model;
    bkf_orbits_param along;
    size_t j, N;
    double tol;
    bkf_floquet_point point;
    bkf_error err;
    int status;
} pd_ctx;

/* lambda of mode j at p, signed so that a real negative multiplier's
 * crossing is a root: lambda where m1 < 0, else -1 (positive or complex
 * dominant multipliers are not this bifurcation). */
static int pd_eval(pd_ctx *c, double p, double *lambda)
{
    bkf_model_params m = c->model;
    orbits_param_set(&m, c->along, p);
    /* floquet's default accuracy whatever tol: the root is cheap, and the
     * branch's start is checked against it */
    bkf_floquet_options fo = bkf_floquet_options_default();
    int s = bkf_floquet_set(c->fl, m.gamma, m.c, m.nu, &fo, &c->err);
    if (!s) s = bkf_floquet_eval(c->fl, orbits_q_effective(&m, c->j, c->N), &c->point, &c->err);
    /* far from the root only lambda's sign counts: an estimate above tol
     * that cannot change it will do */
    if (s == BKF_ETOL && fabs(c->point.lambda) > 10 * c->point.lambda_err) s = BKF_OK;
    c->status = s;
    if (s) return s;
    *lambda = c->point.lambda;
    return BKF_OK;
}

static double pd_fn(double p, void *data)
{
    pd_ctx *c = data;
    double l = NAN;
    if (c->status == BKF_OK) pd_eval(c, p, &l);
    return c->status == BKF_OK ? l : NAN;
}

/* The mode nearest q_c of floquet's threshold at the start (the chain's
 * by its effective wavenumber). */
static int auto_mode(const bkf_model_params *m, size_t *j, bkf_error *err)
{
    /* floquet's own accuracy, whatever tol: a loose one found another
     * boundary first (gamma 3, c 0.8 at tol 1e-3) */
    bkf_floquet_options fo = bkf_floquet_options_default();
    bkf_floquet_threshold th;
    int s = bkf_floquet_threshold_find(m->gamma, m->c, -0.999, 0.999, &fo, &th, err);
    if (s) return s;
    if (th.kind != BKF_BOUNDARY_PERIOD_DOUBLING)
        return bkf_error_set(err, BKF_ENUMERIC,
                             "j: the global oscillation at gamma %g, c %g has no period "
                             "doubling (its lowest boundary is %s); give the mode j",
                             m->gamma, m->c, bkf_floquet_boundary_name(th.kind));
    double jj = floor(th.q * m->S / (2.0 * M_PI) + 0.5);
    *j = jj < 1 ? 1 : (size_t)jj;
    if (m->kind == BKF_MODEL_CHAIN) {
        size_t N = orbits_default_N(m, 1), best = 1;
        for (size_t k = 1; 2 * k <= N; k++)
            if (fabs(orbits_q_effective(m, k, N) - th.q) <
                fabs(orbits_q_effective(m, best, N) - th.q))
                best = k;
        *j = best;
    }
    return BKF_OK;
}

size_t orbits_default_N(const bkf_model_params *m, size_t j)
{
    if (m->N) return m->N;
    if (m->kind == BKF_MODEL_CHAIN) return (size_t)floor(m->S + 0.5);
    return BKF_ORBITS_CELL_POINTS * j;
}

int bkf_orbits_pd_find(const bkf_orbits_options *o, bkf_orbits_pd *pd, bkf_error *err)
{
    if (!o || !pd) return bkf_error_set(err, BKF_EINPUT, "orbits: options or result NULL");
    memset(pd, 0, sizeof *pd);
    bkf_model_params m = o->model;
    orbits_param_set(&m, o->along, o->from);
    size_t j = o->j;
    int s = j ? BKF_OK : auto_mode(&m, &j, err);
    if (s) return s;
    pd_ctx c = {.fl = bkf_floquet_alloc(), .model = o->model, .along = o->along, .j = j,
                .N = orbits_default_N(&o->model, j), .tol = o->tol};
    if (!c.fl) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    double dir = o->to > o->from ? 1.0 : -1.0;
    double step = o->along == BKF_ORBITS_NU ? 0.005 : 0.02 * fabs(o->from);
    double a = o->from, la = NAN;
    s = pd_eval(&c, a, &la);
    if (s && err) *err = c.err;
    if (!s && !(la < 0))
        s = bkf_error_set(err, BKF_ENUMERIC,
                          "from: the global oscillation's mode j = %zu is not stable at %s = %g "
                          "(lambda %g): start the scan where it is",
                          j, bkf_orbits_param_name(o->along), a, la);
    double b = a, lb = la;
    int found = 0;
    while (!s && !found) {
        b = a + dir * step;
        if ((dir > 0 && b > o->to) || (dir < 0 && b < o->to)) b = o->to;
        s = pd_eval(&c, b, &lb);
        if (s) {
            if (err) *err = c.err;
            break;
        }
        if (lb > 0) {
            if (c.point.m1_re < 0 && c.point.kind == BKF_FLOQUET_REAL_NEGATIVE) found = 1;
            else
                s = bkf_error_set(err, BKF_ENUMERIC,
                                  "mode j = %zu loses stability at %s ~ %g through m = %+g, not "
                                  "-1: no period doubling there",
                                  j, bkf_orbits_param_name(o->along), b, c.point.m1_re);
            break;
        }
        if (b == o->to) break;
        a = b;
        la = lb;
    }
    if (!s && !found)
        s = bkf_error_set(err, BKF_ENUMERIC,
                          "no period doubling of mode j = %zu for %s from %g to %g: the "
                          "oscillation stays stable to it",
                          j, bkf_orbits_param_name(o->along), o->from, o->to);
    if (s == BKF_OK) {
        gsl_error_handler_t *old = gsl_set_error_handler_off();
        gsl_root_fsolver *r = gsl_root_fsolver_alloc(gsl_root_fsolver_brent);
        gsl_function F = {pd_fn, &c};
        double lo = fmin(a, b), hi = fmax(a, b);
        double ptol = 1e-12 * fmax(1.0, fabs(o->from));
        if (!r) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
        else if (gsl_root_fsolver_set(r, &F, lo, hi) != GSL_SUCCESS)
            s = c.status ? (*err = c.err, c.status)
                         : bkf_error_set(err, BKF_ENUMERIC, "Brent could not start");
        for (int it = 0; !s && it < 200; it++) {
            gsl_root_fsolver_iterate(r);
            if (c.status) {
                *err = c.err;
                s = c.status;
                break;
            }
            lo = gsl_root_fsolver_x_lower(r);
            hi = gsl_root_fsolver_x_upper(r);
            if (hi - lo <= ptol) break;
        }
        if (!s) {
            double p = gsl_root_fsolver_root(r);
            double l;
            s = pd_eval(&c, p, &l);
            if (s) *err = c.err;
            else {
                bkf_model_params at = o->model;
                orbits_param_set(&at, o->along, p);
                /* the root's error: the bracket, and lambda's error over
                 * the slope of lambda across it */
                double slope = (lb - la) / (b - a);
                pd->model = at;
                pd->p = p;
                pd->p_err = (hi - lo) + fabs(c.point.lambda_err / slope);
                pd->j = j;
                pd->q = 2.0 * M_PI * (double)j / at.S;
                pd->q_eff = orbits_q_effective(&at, j, c.N);
                const bkf_cycle_result *cy = bkf_floquet_cycle(c.fl);
                pd->period = cy->period;
                pd->period_err = cy->period_err;
                pd->m_re = c.point.m1_re;
                pd->lambda = c.point.lambda;
                pd->lambda_err = c.point.lambda_err;
                /* the eigenvector of the monodromy (from the section) for m1 */
                const double *M = c.point.monodromy;
                double m1 = c.point.m1_re;
                double v1[2] = {M[1], m1 - M[0]}, v2[2] = {m1 - M[3], M[2]};
                const double *v = hypot(v1[0], v1[1]) > hypot(v2[0], v2[1]) ? v1 : v2;
                double nv = fmax(fabs(v[0]), fabs(v[1]));
                double sign = fabs(v[0]) >= fabs(v[1]) ? (v[0] < 0 ? -1 : 1) : (v[1] < 0 ? -1 : 1);
                pd->v_psi = sign * v[0] / nv;
                pd->v_eta = sign * v[1] / nv;
                pd->psi0 = at.nu;
                pd->eta0 = cy->section_slope / at.gamma + at.nu * at.nu * at.nu / 3.0 - at.nu;
            }
        }
        gsl_root_fsolver_free(r);
        gsl_set_error_handler(old);
    }
    bkf_floquet_free(c.fl);
    return s;
}

/* ------------------------------------------------------ the continuation */

typedef struct {
    const bkf_orbits_options *o;
    bkf_model_params base;  /* the cell's model but for p */
    size_t m, Nc, K, kc;    /* cells, points per cell, last coefficient, critical one */
    size_t n;               /* equations: 2 (K + 1) + 1 */
    int half;               /* the half-period symmetry is used (one cell per mode
                               wavelength, an even number of points in it) */
    double *cosm;           /* cos(2 pi k i / Nc), (K + 1) x Nc */
    double *psi, *eta, *g0, *g1, *ucache, *jcache;
    int have_jac;
    double *scale;
    bkf_pde *pde;
    double pde_p;           /* the parameter pde was made for */
    size_t flows;
    /* the rows */
    bkf_orbits_visit visit;
    void *data;
    bkf_orbits_report *rep;
    size_t index;
    int skip_next;          /* the second leg's start repeats the first leg's end */
    int stage;
    double *last_u, *last_t;
    int have_last;
    /* the previous row's multipliers outside the circle */
    int prev_has;
    size_t prev_plus, prev_minus, prev_complex;
    bkf_orbit_verdict prev_verdict;
    int stop_status;        /* a failure of the visit's own work (polish: out of memory) */
    bkf_error stop_err;
    double *full_psi, *full_eta;
    bkf_orbit *prev_ob;     /* the last point with multipliers: the next one's Arnoldi
                               starts from its eigenvectors */
    double p0, span;        /* for progress */
    char why[BKF_ERROR_LEN + 32]; /* a row's status when refused */
} cont_ctx;

static double weight(const cont_ctx *c, size_t k)
{
    return (k == 0 || 2 * k == c->Nc) ? 1.0 : 2.0;
}

/* Coefficients a_0..a_K of an even cell field into its values. */
static void to_grid(const cont_ctx *c, const double *a, double *f)
{
    for (size_t i = 0; i < c->Nc; i++) {
        double s = 0.0;
        for (size_t k = 0; k <= c->K; k++) s += weight(c, k) * a[k] * c->cosm[k * c->Nc + i];
        f[i] = s;
    }
}

static void to_coeff(const cont_ctx *c, const double *f, double *a)
{
    for (size_t k = 0; k <= c->K; k++) {
        double s = 0.0;
        for (size_t i = 0; i < c->Nc; i++) s += f[i] * c->cosm[k * c->Nc + i];
        a[k] = s / (double)c->Nc;
    }
}

static int ensure_pde(cont_ctx *c, double p, bkf_error *err)
{
    if (c->pde && c->pde_p == p) return BKF_OK;
    bkf_pde_free(c->pde);
    bkf_model_params m = c->base;
    orbits_param_set(&m, c->o->along, p);
    if (c->o->along == BKF_ORBITS_S) m.S = p / (double)c->m;
    bkf_pde_options po = bkf_pde_options_default();
    po.tol = FLOW_TOL;
    po.max_steps = 2000000;
    po.cancel = c->o->cancel;
    c->pde = bkf_pde_alloc(&m, &po, err);
    c->pde_p = p;
    return c->pde ? BKF_OK : (err ? err->status : BKF_ENOMEM);
}

/* Phi_{P/2} of the cell state u (coefficients), as coefficients into out.
 * The branch keeps the symmetry it is born with: half a period on, the
 * pattern is the same shifted by half a cell, u(x, t + P/2) = u(x + L/2, t)
 * (at the switch the critical mode, cos(q_j x) with multiplier -1, changes
 * sign over T ~ P/2, and a shift by L/2 changes the sign of every odd
 * coefficient, nothing else).  The continuation solves on that subspace at
 * half the cost; the polish and the multipliers take the whole period and
 * the whole state, so a branch that breaks the symmetry shows there (a
 * multiplier through +1 of a mode it does not hold). */
static int flow(cont_ctx *c, const double *u, double *out, bkf_error *err)
{
    size_t K1 = c->K + 1;
    double P = u[2 * K1], p = u[2 * K1 + 1];
    if (!(P > 0) || !isfinite(P) || !isfinite(p))
        return bkf_error_set(err, BKF_ENUMERIC, "period %g not positive", P);
    if (c->o->along == BKF_ORBITS_NU && !(fabs(p) < 1))
        return bkf_error_set(err, BKF_ENUMERIC, "nu %g left the active range", p);
    if (c->o->along != BKF_ORBITS_NU && !(p > 0))
        return bkf_error_set(err, BKF_ENUMERIC, "%s %g not positive",
                             bkf_orbits_param_name(c->o->along), p);
    int s = ensure_pde(c, p, err);
    if (s) return s == BKF_EINPUT ? BKF_ENUMERIC : s;
    to_grid(c, u, c->psi);
    to_grid(c, u + K1, c->eta);
    s = bkf_pde_set_state(c->pde, c->psi, c->eta, 0.0, err);
    double t = c->half ? P / 2 : P;
    if (!s) s = bkf_pde_run(c->pde, t, t, NULL, NULL, NULL, NULL, err);
    c->flows++;
    if (s) return s == BKF_ECANCELED ? s : BKF_ENUMERIC;
    to_coeff(c, bkf_pde_psi(c->pde), out);
    to_coeff(c, bkf_pde_eta(c->pde), out + K1);
    return BKF_OK;
}

static int residual_only(cont_ctx *c, const double *u, double *g, bkf_error *err)
{
    size_t K1 = c->K + 1;
    int s = flow(c, u, g, err);
    if (s) return s;
    /* the half-cell shift: odd coefficients change sign */
    for (size_t i = 0; i < 2 * K1; i++) g[i] -= c->half && (i % K1) % 2 ? -u[i] : u[i];
    double nu = c->o->along == BKF_ORBITS_NU ? u[2 * K1 + 1] : c->base.nu;
    g[2 * K1] = u[0] - nu;
    return BKF_OK;
}

static int residual(const double *u, double *g, double *jac, void *data, bkf_error *err)
{
    cont_ctx *c = data;
    if (c->o->cancel && *c->o->cancel)
        return bkf_error_set(err, BKF_ECANCELED, "canceled");
    int s = residual_only(c, u, g, err);
    if (s || !jac) return s;
    size_t n = c->n, N = n + 1;
    if (c->have_jac) {
        double d = 0.0;
        for (size_t i = 0; i < N; i++) d = fmax(d, fabs(u[i] - c->ucache[i]) / c->scale[i]);
        if (d <= JAC_REUSE) {
            memcpy(jac, c->jcache, n * N * sizeof *jac);
            return BKF_OK;
        }
    }
    double *uh = c->ucache; /* rebuilt below */
    memcpy(uh, u, N * sizeof *uh);
    for (size_t j = 0; j < N; j++) {
        double h = FD_STEP * fmax(fabs(u[j]), 1.0);
        uh[j] = u[j] + h;
        s = residual_only(c, uh, c->g0, err);
        uh[j] = u[j];
        if (s) {
            c->have_jac = 0;
            return s;
        }
        for (size_t i = 0; i < n; i++) jac[i * N + j] = (c->g0[i] - g[i]) / h;
    }
    memcpy(c->jcache, jac, n * N * sizeof *jac);
    c->have_jac = 1;
    return BKF_OK;
}


/* ------------------------------------------------------------- the rows */

typedef struct {
    size_t N;
    double amp;
} amp_obs;

static int amp_observe(const bkf_pde_sample *smp, void *data)
{
    amp_obs *a = data;
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < a->N; i++) {
        lo = fmin(lo, smp->psi[i]);
        hi = fmax(hi, smp->psi[i]);
    }
    a->amp = fmax(a->amp, hi - lo);
    return 0;
}

/* The spatial range of psi, largest over one period, of the cell state. */
static int amplitude_of(cont_ctx *c, double p, const double *psi, const double *eta, double P,
                        double *amp, bkf_error *err)
{
    int s = ensure_pde(c, p, err);
    if (s) return s;
    amp_obs a = {c->Nc, 0.0};
    s = bkf_pde_set_state(c->pde, psi, eta, 0.0, err);
    if (!s) s = bkf_pde_run(c->pde, P, P / 400.0, amp_observe, &a, NULL, NULL, err);
    c->flows++;
    *amp = s ? NAN : a.amp;
    return s;
}

const char *bkf_orbits_events_text(unsigned ev, char *buf, size_t size)
{
    static const char *const names[] = {"fold", "period_doubling", "torus", "real",
                                        "stability_change"};
    size_t used = 0;
    if (size) buf[0] = '\0';
    for (unsigned i = 0; i < 5; i++) {
        if (!(ev & (1u << i))) continue;
        int w = snprintf(buf + used, size > used ? size - used : 0, "%s%s", used ? "+" : "",
                         names[i]);
        if (w > 0) used += (size_t)w;
    }
    if (!used && size) snprintf(buf, size, "-");
    return buf;
}

/* The multipliers outside the unit circle, and the largest physical one. */
static void count_outside(const bkf_orbit_spectrum *sp, bkf_orbits_point *pt)
{
    pt->out_plus = pt->out_minus = pt->out_complex = 0;
    pt->m_abs = pt->m_re = pt->m_im = pt->m_err = NAN;
    for (size_t i = 0; i < sp->count; i++) {
        const bkf_orbit_multiplier *m = &sp->m[i];
        if (m->kind != BKF_ORBIT_MULT_PHYSICAL) continue;
        if (!(m->abs > 1)) continue;
        if (fabs(m->im) <= m->err) {
            if (m->re > 0) pt->out_plus++;
            else pt->out_minus++;
        } else if (m->im > 0) {
            pt->out_complex++;
        }
    }
    if (sp->largest_index < sp->count) {
        const bkf_orbit_multiplier *m = &sp->m[sp->largest_index];
        pt->m_abs = m->abs;
        pt->m_re = m->re;
        pt->m_im = m->im;
        pt->m_err = m->err;
    }
}

static int emit(cont_ctx *c, bkf_orbits_point *pt)
{
    if (pt->has_spectrum) {
        if (c->prev_has) {
            if (pt->out_minus != c->prev_minus) pt->events |= BKF_ORBITS_EV_PERIOD_DOUBLING;
            if (pt->out_complex != c->prev_complex) pt->events |= BKF_ORBITS_EV_TORUS;
            if (pt->out_plus != c->prev_plus) pt->events |= BKF_ORBITS_EV_REAL;
            if (pt->verdict != BKF_ORBIT_UNDECIDED && c->prev_verdict != BKF_ORBIT_UNDECIDED &&
                pt->verdict != c->prev_verdict)
                pt->events |= BKF_ORBITS_EV_STABILITY;
        }
        c->prev_has = 1;
        c->prev_plus = pt->out_plus;
        c->prev_minus = pt->out_minus;
        c->prev_complex = pt->out_complex;
        if (pt->verdict != BKF_ORBIT_UNDECIDED) c->prev_verdict = pt->verdict;
    }
    pt->index = c->index++;
    pt->report = c->rep;
    int stop = c->visit ? c->visit(pt, c->data) : 0;
    if (c->o->progress) {
        double f = (double)c->index / (double)(c->o->max_points + 1);
        if (c->span > 0) f = fmax(f, fabs(pt->p - c->p0) / c->span);
        if (c->o->progress(fmin(f, 1.0), c->o->progress_data)) stop = 1;
    }
    return stop;
}

/* A point of the continuation: polished on the full domain, judged, passed on. */
static int accept(const double *u, const double *tangent, int is_fold, void *data)
{
    cont_ctx *c = data;
    size_t K1 = c->K + 1, N = c->n + 1;
    memcpy(c->last_u, u, N * sizeof *u);
    memcpy(c->last_t, tangent, N * sizeof *tangent);
    c->have_last = 1;
    if (c->skip_next && !is_fold) {
        c->skip_next = 0;
        return 0;
    }
    /* no pattern left: the corrector found the global oscillation */
    double pattern = 0;
    for (size_t k = 1; k < K1; k++) pattern = fmax(pattern, fabs(u[k]));
    if (pattern < 1e-3 * c->o->switch_amplitude) {
        c->stop_status = bkf_error_set(&c->stop_err, BKF_ENUMERIC,
                                       "the continuation fell back onto the global oscillation "
                                       "at %s = %.10g (a step too long near a fold?)",
                                       bkf_orbits_param_name(c->o->along), u[2 * K1 + 1]);
        return 1;
    }
    if (c->o->cancel && *c->o->cancel) return 1;
    if (is_fold) c->rep->folds++;
    else c->rep->points++;
    double P = u[2 * K1], p = u[2 * K1 + 1];
    bkf_orbits_point pt;
    memset(&pt, 0, sizeof pt);
    pt.is_fold = is_fold;
    pt.events = is_fold ? BKF_ORBITS_EV_FOLD : 0;
    pt.p = p;
    pt.cont_period = P;
    pt.mode_amplitude = weight(c, c->kc) * u[c->kc];
    pt.model = c->o->model;
    pt.model.N = c->m * c->Nc;
    orbits_param_set(&pt.model, c->o->along, p);
    pt.period = pt.period_err = pt.shift = pt.amplitude = pt.err = NAN;
    pt.m_abs = pt.m_re = pt.m_im = pt.m_err = NAN;
    pt.verdict = BKF_ORBIT_UNDECIDED;
    pt.status = "ok";
    to_grid(c, u, c->psi);
    to_grid(c, u + K1, c->eta);
    size_t Nf = c->m * c->Nc;
    for (size_t i = 0; i < Nf; i++) {
        c->full_psi[i] = c->psi[i % c->Nc];
        c->full_eta[i] = c->eta[i % c->Nc];
    }
    bkf_orbit_options oo = bkf_orbit_options_default();
    oo.tol = c->o->tol;
    oo.cells = c->m;
    oo.shift_mode = pt.model.kind == BKF_MODEL_CHAIN ? BKF_ORBIT_SHIFT_NONE : BKF_ORBIT_SHIFT_FREE;
    oo.cancel = c->o->cancel;
    bkf_error e = {0};
    bkf_orbit *ob = bkf_orbit_alloc(&pt.model, &oo, &e);
    bkf_orbit_result res;
    bkf_orbit_spectrum sp;
    int s = ob ? BKF_OK : e.status;
    if (!s) {
        bkf_orbit_guess g = {c->full_psi, c->full_eta, P, 0.0};
        s = bkf_orbit_solve(ob, &g, &res, &e);
    }
    if (s == BKF_ENOMEM || s == BKF_ECANCELED) {
        c->stop_status = s;
        c->stop_err = e;
        bkf_orbit_free(ob);
        return 1;
    }
    if (s == BKF_OK) {
        pt.period = res.period;
        pt.period_err = res.err;
        pt.shift = res.shift;
        pt.err = res.err;
        pt.orbit = &res;
        pt.psi = bkf_orbit_psi(ob);
        pt.eta = bkf_orbit_eta(ob);
        int sa = amplitude_of(c, p, pt.psi, pt.eta, res.period, &pt.amplitude, &e);
        if (sa == BKF_ECANCELED) {
            c->stop_status = sa;
            c->stop_err = e;
            bkf_orbit_free(ob);
            return 1;
        }
        if (c->o->stability) {
            bkf_orbit_mult_options mo = bkf_orbit_mult_options_default();
            mo.k = c->o->k;
            mo.warm_start = c->prev_ob;
            int sm = bkf_orbit_multipliers(ob, &mo, &sp, &e);
            if (sm == BKF_ENOMEM || sm == BKF_ECANCELED) {
                c->stop_status = sm;
                c->stop_err = e;
                bkf_orbit_free(ob);
                return 1;
            }
            if (sm == BKF_OK) {
                bkf_orbit_free(c->prev_ob);
                c->prev_ob = ob; /* freed with the context or the next such point */
                pt.has_spectrum = 1;
                pt.spectrum = &sp;
                pt.verdict = sp.verdict;
                count_outside(&sp, &pt);
            } else {
                snprintf(c->why, sizeof c->why, "multipliers: %s", e.message);
                pt.status = c->why;
            }
        }
    } else {
        c->rep->refused++;
        snprintf(c->why, sizeof c->why, "%s", e.message);
        pt.status = c->why;
    }
    int stop = emit(c, &pt);
    if (ob != c->prev_ob) bkf_orbit_free(ob);
    return stop;
}

static void orbits_ctx_free(cont_ctx *c)
{
    free(c->cosm);
    free(c->psi);
    free(c->eta);
    free(c->g0);
    free(c->g1);
    free(c->ucache);
    free(c->jcache);
    free(c->scale);
    free(c->last_u);
    free(c->last_t);
    free(c->full_psi);
    free(c->full_eta);
    bkf_pde_free(c->pde);
    bkf_orbit_free(c->prev_ob);
}

bkf_orbits_options bkf_orbits_options_default(void)
{
    bkf_orbits_options o;
    memset(&o, 0, sizeof o);
    o.model = bkf_model_params_paper();
    o.model.N = 0;
    o.j = 0;
    o.along = BKF_ORBITS_NU;
    o.from = -0.90;
    o.to = -0.999;
    o.max_points = 50;
    o.tol = 1e-3;
    o.step = 0.5;
    o.stability = 1;
    o.k = 2;
    o.switch_amplitude = 0.02;
    return o;
}

static int check_options(const bkf_orbits_options *o, bkf_error *err)
{
    if (!o) return bkf_error_set(err, BKF_EINPUT, "orbits: options NULL");
    if ((unsigned)o->along > BKF_ORBITS_S)
        return bkf_error_set(err, BKF_EINPUT, "along: not nu, gamma, c or S");
    if (!(isfinite(o->from) && isfinite(o->to) && o->from != o->to))
        return bkf_error_set(err, BKF_EINPUT, "from, to: two different finite values");
    if (!(o->tol >= BKF_ORBIT_TOL_MIN && o->tol <= BKF_ORBIT_TOL_MAX))
        return bkf_error_set(err, BKF_EINPUT, "tol: not in [%g, %g]", BKF_ORBIT_TOL_MIN,
                             BKF_ORBIT_TOL_MAX);
    if (!(o->step > 0 && o->step <= 10))
        return bkf_error_set(err, BKF_EINPUT, "step: not in (0, 10]");
    if (o->max_points < SWITCH_POINTS + 1 || o->max_points > BKF_ORBITS_POINTS_MAX)
        return bkf_error_set(err, BKF_EINPUT, "max-points: not in [%d, %u]", SWITCH_POINTS + 1,
                             BKF_ORBITS_POINTS_MAX);
    if (o->stability && o->k < 1) return bkf_error_set(err, BKF_EINPUT, "k: at least 1");
    if (!(o->switch_amplitude > 0 && o->switch_amplitude <= 0.5))
        return bkf_error_set(err, BKF_EINPUT, "switch-amplitude: not in (0, 0.5]");
    double lo = fmin(o->from, o->to), hi = fmax(o->from, o->to);
    if (o->along == BKF_ORBITS_NU && !(lo > -1 && hi < 1))
        return bkf_error_set(err, BKF_EINPUT, "from, to: nu must stay in (-1, 1)");
    if (o->along == BKF_ORBITS_C && !(lo > 0))
        return bkf_error_set(err, BKF_EINPUT, "from, to: c must stay > 0");
    if (o->along != BKF_ORBITS_NU && o->along != BKF_ORBITS_C && !(lo > 0))
        return bkf_error_set(err, BKF_EINPUT, "from, to: %s must stay > 0",
                             bkf_orbits_param_name(o->along));
    return BKF_OK;
}

/* The grid of the branch: N on the whole ring and m cells (j on the
 * continuum, whose cell needs an even number of points). */
static int branch_grid(const bkf_orbits_options *o, const bkf_orbits_pd *pd, size_t *N_out,
                       size_t *m_out, bkf_error *err)
{
    size_t N = orbits_default_N(&o->model, pd->j), m;
    if (o->model.kind == BKF_MODEL_CHAIN) {
        m = N % pd->j == 0 ? pd->j : 1;
    } else {
        if (N % (2 * pd->j) != 0)
            return bkf_error_set(err, BKF_EINPUT,
                                 "N: the continuum's N must be a multiple of 2 j = %zu (the "
                                 "orbit is solved on one of j = %zu cells with an even number "
                                 "of points)",
                                 2 * pd->j, pd->j);
        m = pd->j;
    }
    if (N / m < BKF_PDE_N_MIN || pd->j / m > N / m / 2)
        return bkf_error_set(err, BKF_EINPUT,
                             "N: %zu points per cell cannot hold mode j = %zu (at least %d)",
                             N / m, pd->j, BKF_PDE_N_MIN);
    *N_out = N;
    *m_out = m;
    return BKF_OK;
}

/* The context's geometry, buffers, cosine table and scales. */
static int ctx_init(cont_ctx *c, const bkf_orbits_options *o, bkf_orbits_report *rep, size_t N,
                    size_t m, bkf_error *err)
{
    const bkf_orbits_pd *pd = &rep->pd;
    memset(c, 0, sizeof *c);
    c->o = o;
    c->m = m;
    c->Nc = N / m;
    c->K = c->Nc / 2;
    c->kc = pd->j / m;
    c->n = 2 * (c->K + 1) + 1;
    c->half = c->kc == 1 && c->Nc % 2 == 0;
    c->base = pd->model;
    c->base.N = c->Nc;
    c->base.S = pd->model.S / (double)m;
    c->rep = rep;
    c->p0 = pd->p;
    c->span = fmax(fabs(o->to - pd->p), fabs(o->from - pd->p));
    size_t Nu = c->n + 1, K1 = c->K + 1;
    c->cosm = malloc(K1 * c->Nc * sizeof *c->cosm);
    c->psi = malloc(c->Nc * sizeof *c->psi);
    c->eta = malloc(c->Nc * sizeof *c->eta);
    c->g0 = malloc(c->n * sizeof *c->g0);
    c->g1 = malloc(c->n * sizeof *c->g1);
    c->ucache = malloc(Nu * sizeof *c->ucache);
    c->jcache = malloc(c->n * Nu * sizeof *c->jcache);
    c->scale = malloc(Nu * sizeof *c->scale);
    c->last_u = malloc(Nu * sizeof *c->last_u);
    c->last_t = malloc(Nu * sizeof *c->last_t);
    c->full_psi = malloc(N * sizeof *c->full_psi);
    c->full_eta = malloc(N * sizeof *c->full_eta);
    if (!c->cosm || !c->psi || !c->eta || !c->g0 || !c->g1 || !c->ucache || !c->jcache ||
        !c->scale || !c->last_u || !c->last_t || !c->full_psi || !c->full_eta)
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    for (size_t k = 0; k < K1; k++)
        for (size_t i = 0; i < c->Nc; i++)
            c->cosm[k * c->Nc + i] = cos(2.0 * M_PI * (double)((k * i) % c->Nc) / (double)c->Nc);
    /* The scales weigh the pattern (every coefficient k >= 1) as heavily as
     * nu: the uniform oscillation, a solution at every nu too, is then
     * many steps away from any point of the branch, so the corrector does
     * not fall back onto it near a fold. */
    for (size_t i = 0; i < 2 * K1; i++) c->scale[i] = i % K1 ? 0.01 : 0.1;
    c->scale[2 * K1] = 0.1;
    c->scale[2 * K1 + 1] = o->along == BKF_ORBITS_NU ? 0.01 : 0.01 * fabs(pd->p);
    return BKF_OK;
}

/* Row 0: the oscillation where it doubles; its period-2T orbit. */
static int emit_start(cont_ctx *c, size_t N)
{
    const bkf_orbits_pd *pd = &c->rep->pd;
    bkf_orbits_point pt0;
    memset(&pt0, 0, sizeof pt0);
    pt0.is_start = 1;
    pt0.model = pd->model;
    pt0.model.N = N;
    pt0.p = pd->p;
    pt0.period = 2 * pd->period;
    pt0.period_err = 2 * pd->period_err;
    pt0.cont_period = pt0.period;
    pt0.shift = 0;
    pt0.amplitude = 0;
    pt0.err = pd->p_err;
    pt0.status = "bifurcation";
    pt0.verdict = BKF_ORBIT_UNDECIDED;
    pt0.m_abs = fabs(pd->m_re);
    pt0.m_re = pd->m_re;
    pt0.m_im = 0;
    pt0.m_err = pd->lambda_err;
    pt0.events = BKF_ORBITS_EV_PERIOD_DOUBLING;
    return emit(c, &pt0);
}

/* The first leg: the critical mode's amplitude held.  Near |nu| = 1 the
 * cycle is small and the amplitude may be too large for the corrector (it
 * left the active range at gamma 8, c 1.5, S 60): it is halved, at most
 * three times, while the start alone fails. */
static int first_leg(cont_ctx *c, double *u0, bkf_cont_options *co, bkf_error *err)
{
    const bkf_orbits_pd *pd = &c->rep->pd;
    size_t Nu = c->n + 1, K1 = c->K + 1;
    double w = weight(c, c->kc), amp = c->o->switch_amplitude;
    int held = fabs(pd->v_psi) >= fabs(pd->v_eta) ? (int)c->kc : (int)(K1 + c->kc);
    bkf_cont_report cr;
    int s = BKF_OK;
    for (int attempt = 0; attempt < 4; attempt++, amp /= 2) {
        memset(u0, 0, Nu * sizeof *u0);
        u0[0] = pd->psi0;
        u0[K1] = pd->eta0;
        u0[c->kc] += amp * pd->v_psi / w;
        u0[K1 + c->kc] += amp * pd->v_eta / w;
        u0[2 * K1] = 2 * pd->period;
        u0[2 * K1 + 1] = pd->p;
        *co = bkf_cont_options_default(c->n);
        co->scale = c->scale;
        co->newton_tol = 1e-9;
        co->newton_max_iter = 12;
        co->step_initial = amp / (2 * w);
        co->step_max = amp / w;
        co->step_min = 1e-8;
        co->max_points = SWITCH_POINTS;
        c->stage = 1;
        s = bkf_cont_run(residual, accept, c, u0, held, u0[held] > 0 ? 1 : -1, co, &cr, err);
        if (c->stop_status || s != BKF_ENUMERIC || c->rep->points > 0) break;
    }
    return s;
}

/* The second leg: along p, away from the oscillation, from the first
 * leg's last point. */
static int second_leg(cont_ctx *c, double *u0, bkf_cont_options *co, bkf_error *err)
{
    const bkf_orbits_options *o = c->o;
    size_t Nu = c->n + 1, K1 = c->K + 1;
    if (!c->have_last || c->rep->points != SWITCH_POINTS || c->last_t[2 * K1 + 1] == 0)
        return BKF_OK;
    int dir = c->last_t[2 * K1 + 1] > 0 ? 1 : -1;
    memcpy(u0, c->last_u, Nu * sizeof *u0);
    co->step_initial = fmin(o->step, 0.05);
    co->step_max = o->step;
    /* every point is solved again to tol by module orbit: the branch needs
     * only to pass close enough for that (and the steps grow only when
     * Newton takes two iterations) */
    co->newton_tol = 1e-7;
    co->max_points = o->max_points - SWITCH_POINTS + 1;
    co->stop_index = (int)(2 * K1 + 1);
    co->stop_min = fmin(o->from, o->to);
    co->stop_max = fmax(o->from, o->to);
    c->skip_next = 1;
    c->stage = 2;
    bkf_cont_report cr;
    int s = bkf_cont_run(residual, accept, c, u0, (int)(2 * K1 + 1), dir, co, &cr, err);
    c->rep->reached_bound = cr.reached_bound;
    return s;
}

int bkf_orbits_branch(const bkf_orbits_options *o, bkf_orbits_visit visit, void *data,
                      bkf_orbits_report *report, bkf_error *err)
{
    bkf_orbits_report rep_local;
    bkf_orbits_report *rep = report ? report : &rep_local;
    memset(rep, 0, sizeof *rep);
    size_t N = 0, m = 1;
    int s = check_options(o, err);
    if (!s) s = bkf_orbits_pd_find(o, &rep->pd, err);
    if (!s) s = branch_grid(o, &rep->pd, &N, &m, err);
    if (s) return s;
    rep->cells = m;
    rep->N = N;
    rep->cell_points = N / m;
    cont_ctx c;
    double *u0 = NULL;
    s = ctx_init(&c, o, rep, N, m, err);
    if (!s && !(u0 = calloc(c.n + 1, sizeof *u0)))
        s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    c.visit = visit;
    c.data = data;
    bkf_cont_options co;
    int stop = s ? 1 : emit_start(&c, N);
    if (!stop) s = first_leg(&c, u0, &co, err);
    if (!s && !c.stop_status) s = second_leg(&c, u0, &co, err);
    if (c.stop_status) {
        s = c.stop_status;
        if (err) *err = c.stop_err;
    }
    rep->flows = c.flows;
    free(u0);
    orbits_ctx_free(&c);
    return s;
}
