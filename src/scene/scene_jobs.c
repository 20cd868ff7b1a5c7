/* A plan run on threads (bkf_scene_run): which step starts when, the
 * hooks shared between workers. */
#define _POSIX_C_SOURCE 200809L
#include "scene_internal.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* ------------------------------------------------------------------ jobs */

/* Threads, not forked workers: every product is safe to call from two
 * threads at once (a sweep already runs them on OpenMP threads; FFTW's
 * planner is behind bkf_fft_lock, GSL's error handler behind a depth count,
 * the HDF5 calls behind their lock), the signal handler's cancel flag
 * reaches every step without a pipe, and a step's status, message and
 * warnings need no marshalling.  A step writes its own files atomically,
 * so what two steps write never meets. */

enum { STEP_PENDING = 0, STEP_RUNNING, STEP_ENDED };

typedef struct {
    const bkf_scene *s;
    const bkf_scene_plan *plan;
    const bkf_scene_run_options *o;
    int *status;              /* the caller's: written once a step ends */
    int *state;               /* STEP_*, under lock */
    size_t *order;            /* the steps in the order they are started */
    size_t next;              /* no pending step before order[next] */
    size_t running;
    pthread_mutex_t lock;     /* the schedule and the reports */
    pthread_mutex_t hook_lock; /* the caller's hooks, one call at a time */
    pthread_cond_t changed;
} run_queue;

/* One worker's view of the hooks: warnings kept for its step's report,
 * the rest passed on to the caller's, one call at a time. */
typedef struct {
    run_queue *q;
    char warning[BKF_SCENE_WARNINGS][BKF_ERROR_LEN];
    const char *warnings[BKF_SCENE_WARNINGS];
    size_t nwarnings;
} run_worker;

static void worker_warn(const char *message, void *data)
{
    run_worker *w = data;
    /* (a product may warn from threads of its own, a sweep's) */
    pthread_mutex_lock(&w->q->hook_lock);
    if (w->nwarnings < BKF_SCENE_WARNINGS) {
        snprintf(w->warning[w->nwarnings], sizeof w->warning[0], "%s", message);
        w->warnings[w->nwarnings] = w->warning[w->nwarnings];
    }
    w->nwarnings++;
    pthread_mutex_unlock(&w->q->hook_lock);
}

static int worker_progress(double fraction, void *data)
{
    run_worker *w = data;
    const bkf_scene_run_options *o = w->q->o;
    pthread_mutex_lock(&w->q->hook_lock);
    int r = o->hooks.progress(fraction, o->hooks.data);
    pthread_mutex_unlock(&w->q->hook_lock);
    return r;
}

static void worker_hook_temp(const char *path, int armed, void *data)
{
    run_worker *w = data;
    const bkf_scene_run_options *o = w->q->o;
    pthread_mutex_lock(&w->q->hook_lock);
    o->hooks.temp_file(path, armed, o->hooks.data);
    pthread_mutex_unlock(&w->q->hook_lock);
}

static void worker_table_temp(const char *path, int armed, void *data)
{
    run_worker *w = data;
    const bkf_scene_run_options *o = w->q->o;
    pthread_mutex_lock(&w->q->hook_lock);
    o->temp_file(path, armed, o->data);
    pthread_mutex_unlock(&w->q->hook_lock);
}

static int canceled(const bkf_scene_run_options *o)
{
    return o->hooks.cancel && *o->hooks.cancel;
}

/* Whether step i may start: a figure once every step of its data ended
 * (done or failed: bkf_scene_run_step skips it when its data failed). */
static int step_ready(const run_queue *q, size_t i)
{
    const bkf_scene_step *step = &q->plan->steps[i];
    if (step->kind != BKF_SCENE_STEP_FIGURE) return 1;
    for (size_t d = 0; d < step->ndata; d++) {
        const bkf_scene_product_plan *dp = &q->plan->products[step->data_products[d]];
        for (size_t k = 0; k < dp->nsteps; k++)
            if (dp->steps[k] != i && q->state[dp->steps[k]] != STEP_ENDED) return 0;
    }
    return 1;
}

/* The first pending step in q->order that may start, or nsteps when none
 * may now; under lock. */
static size_t next_step(run_queue *q)
{
    size_t n = q->plan->nsteps;
    while (q->next < n && q->state[q->order[q->next]] != STEP_PENDING) q->next++;
    for (size_t k = q->next; k < n; k++) {
        size_t i = q->order[k];
        if (q->state[i] == STEP_PENDING && step_ready(q, i)) return i;
    }
    return n;
}

typedef struct {
    double cost;
    size_t step;
} costed_step;

static int by_cost(const void *a, const void *b)
{
    const costed_step *x = a, *y = b;
    if (x->cost != y->cost) return x->cost > y->cost ? -1 : 1;
    return (x->step > y->step) - (x->step < y->step);
}

/* The order the steps start in: one job runs them in the plan's order (as
 * --plan lists them); several start the longest expected first, so that
 * the longest does not start last and keep one core busy alone at the end
 * (the paper scene's diagram, three quarters of its work, is its 21st of 35
 * steps).  A figure waits for its data either way.  0: out of memory. */
static int start_order(const bkf_scene_plan *plan, size_t jobs, size_t *order)
{
    size_t n = plan->nsteps;
    for (size_t i = 0; i < n; i++) order[i] = i;
    if (jobs < 2 || n < 2) return 1;
    costed_step *c = malloc(n * sizeof *c);
    if (!c) return 0;
    for (size_t i = 0; i < n; i++) c[i] = (costed_step){bkf_scene_step_cost(&plan->steps[i]), i};
    qsort(c, n, sizeof *c, by_cost);
    for (size_t i = 0; i < n; i++) order[i] = c[i].step;
    free(c);
    return 1;
}

static void *run_worker_loop(void *arg)
{
    run_queue *q = arg;
    const bkf_scene_run_options *o = q->o;
    run_worker w = {.q = q};
    bkf_scene_run_options mine = *o;
    mine.hooks.warn = worker_warn;
    mine.hooks.data = &w;
    mine.hooks.progress = o->hooks.progress ? worker_progress : NULL;
    mine.hooks.temp_file = o->hooks.temp_file ? worker_hook_temp : NULL;
    mine.temp_file = o->temp_file ? worker_table_temp : NULL;
    mine.data = &w;
    size_t n = q->plan->nsteps;
    pthread_mutex_lock(&q->lock);
    for (;;) {
        size_t i = n;
        while (!canceled(o) && q->next < n && (i = next_step(q)) == n && q->running)
            pthread_cond_wait(&q->changed, &q->lock);
        if (canceled(o) || i == n) break;
        q->state[i] = STEP_RUNNING;
        q->running++;
        pthread_mutex_unlock(&q->lock);

        bkf_error e = {0};
        char gnuplot[BKF_ERROR_LEN] = "";
        struct timespec t0, t1;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        /* status[] of this step's data is final (they ended before it
         * started); the entries others are writing are not read. */
        int st = bkf_scene_run_step(q->s, q->plan, i, q->status, &mine, gnuplot, sizeof gnuplot,
                                    &e);
        clock_gettime(CLOCK_MONOTONIC, &t1);
        /* A step that failed once the flag was up was stopped, not wrong;
         * one that finished anyway is complete and kept. */
        if (st && canceled(o)) {
            st = BKF_ECANCELED;
            snprintf(e.message, sizeof e.message, "stopped; its files were not replaced");
        }

        pthread_mutex_lock(&q->lock);
        q->status[i] = st;
        q->state[i] = STEP_ENDED;
        q->running--;
        if (o->step_done) {
            bkf_scene_step_report r = {
                .step = i,
                .status = st,
                .seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec),
                .message = st ? e.message : "",
                .gnuplot_warning = st ? "" : gnuplot,
                .warnings = w.warnings,
                .nwarnings = w.nwarnings};
            o->step_done(&r, o->data);
        }
        w.nwarnings = 0;
        pthread_cond_broadcast(&q->changed);
    }
    pthread_cond_broadcast(&q->changed);
    pthread_mutex_unlock(&q->lock);
    return NULL;
}

/* Which failure a run reports when several steps fail. */
static int severity(int status)
{
    switch (status) {
    case BKF_OK: return 0;
    case BKF_ENOMEM: return 4;
    case BKF_ECANCELED: return 3;
    case BKF_EINPUT: return 2;
    default: return 1;
    }
}

int bkf_scene_run_status(const int *status, size_t n)
{
    int worst = BKF_OK;
    for (size_t i = 0; status && i < n; i++)
        if (severity(status[i]) > severity(worst)) worst = status[i];
    return worst;
}

int bkf_scene_run(const bkf_scene *s, const bkf_scene_plan *plan,
                  const bkf_scene_run_options *options, int *status, bkf_error *err)
{
    static const bkf_scene_run_options none = {0};
    const bkf_scene_run_options *o = options ? options : &none;
    if (!s || !plan || (plan->nsteps && !status))
        return bkf_error_set(err, BKF_EINPUT, "scene: no plan to run");
    size_t n = plan->nsteps;
    run_queue q = {.s = s, .plan = plan, .o = o, .status = status};
    size_t jobs = o->jobs > 1 ? o->jobs : 1;
    if (jobs > n) jobs = n ? n : 1;
    q.state = calloc(n ? n : 1, sizeof *q.state);
    q.order = malloc((n ? n : 1) * sizeof *q.order);
    if (!q.state || !q.order || !start_order(plan, jobs, q.order)) {
        free(q.state);
        free(q.order);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    for (size_t i = 0; i < n; i++) status[i] = BKF_ECANCELED; /* until it is run */
    pthread_mutex_init(&q.lock, NULL);
    pthread_mutex_init(&q.hook_lock, NULL);
    pthread_cond_init(&q.changed, NULL);

    /* The caller's thread is one of the workers; a thread that cannot be
     * made leaves the steps to the others (at worst the caller's alone). */
    pthread_t *threads = jobs > 1 ? calloc(jobs - 1, sizeof *threads) : NULL;
    size_t started = 0;
    for (size_t t = 0; threads && t + 1 < jobs; t++) {
        if (pthread_create(&threads[t], NULL, run_worker_loop, &q) != 0) break;
        started++;
    }
    run_worker_loop(&q);
    for (size_t t = 0; t < started; t++) pthread_join(threads[t], NULL);
    free(threads);

    int unrun = 0;
    for (size_t i = 0; i < n; i++) unrun |= q.state[i] != STEP_ENDED;
    pthread_cond_destroy(&q.changed);
    pthread_mutex_destroy(&q.hook_lock);
    pthread_mutex_destroy(&q.lock);
    free(q.state);
    free(q.order);
    if (unrun) return bkf_error_set(err, BKF_ECANCELED, "stopped before every step was run");
    return BKF_OK;
}
