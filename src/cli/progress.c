/* The progress bar (progress.h). */
#define _POSIX_C_SOURCE 200809L
#include "progress.h"

#include <math.h>
#include <stddef.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

const bkf_option cli_progress_options[] = {
    {.name = "no-progress", .type = BKF_OPT_SWITCH, .offset = offsetof(cli_progress_spec, no_progress),
     .flags = BKF_OPT_CLI_ONLY,
     .help = "no progress bar (drawn on stderr only when it is a\n"
             "terminal and the run takes over half a second)"},
};
const size_t cli_progress_noptions = 1;

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ------------------------------------------------------------ progress */


void progress_init(progress_bar *p, const char *label, int allowed)
{
    memset(p, 0, sizeof *p);
    p->enabled = allowed && isatty(STDERR_FILENO);
    p->start = now_seconds();
    p->label = label;
    p->share = 1.0;
}

/* The bar at fraction f, then `tail` (may be empty). */
static void draw(progress_bar *p, double f, double t, const char *tail)
{
    if (f > 1) f = 1;
    int width = 30, done = (int)(f * width + 0.5);
    char bar[64];
    for (int i = 0; i < width; i++) bar[i] = i < done ? '#' : '.';
    bar[width] = '\0';
    fprintf(stderr, "\r%s [%s] %3.0f%%  %.1fs%s\033[K", p->label, bar, 100 * f, t - p->start, tail);
    fflush(stderr);
    p->drawn = 1;
}

/* Whether to draw now: after half a second, at most ten times a second. */
static int due(progress_bar *p, double t)
{
    if (!p->enabled || t - p->start < 0.5 || t - p->last < 0.1) return 0;
    p->last = t;
    return 1;
}

int progress_draw(double fraction, void *data)
{
    progress_bar *p = data;
    double t = now_seconds();
    if (due(p, t)) draw(p, p->base + p->share * fraction, t, "");
    return 0;
}

void progress_count(progress_bar *p, size_t done, size_t total)
{
    double t = now_seconds();
    if (!total || (done < total && !due(p, t))) return;
    if (!p->enabled) return;
    p->last = t;
    char tail[96];
    /* the rate so far: points take similar times on average over a grid */
    double eta = done ? (t - p->start) * (double)(total - done) / (double)done : NAN;
    if (done)
        snprintf(tail, sizeof tail, ", %zu/%zu points, ETA %.0fs", done, total, eta);
    else
        snprintf(tail, sizeof tail, ", %zu/%zu points", done, total);
    draw(p, (double)done / (double)total, t, tail);
}

void progress_end(progress_bar *p)
{
    if (p->drawn) {
        fprintf(stderr, "\r\033[K");
        fflush(stderr);
    }
    p->drawn = 0;
}

/* ---------------------------------------------------- shared parameters */
