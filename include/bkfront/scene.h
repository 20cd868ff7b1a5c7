/* Scenes: what a user wants computed, as an INI file, the lazy plan, and
 * its steps carried out by the library's products.
 *
 * A scene has a [model] section (gamma, c, nu, S, model), an optional
 * [accuracy] section (tol, N) and one section per product, [KIND] or
 * [KIND NAME]:
 *
 *   speeds      table of allowed front speeds        (product speeds)
 *   period      T(mu) beside its asymptotics, per nu (period)
 *   dispersion  Floquet dispersion relations, per nu (floquet)
 *   threshold   stability threshold nu_pd, or its curve (floquet --threshold)
 *   branch      speed branches by continuation, per n (branch)
 *   profile     front profiles f(z), f'(z), per n    (profile)
 *   validity    errors of the asymptotics on a grid  (asymptotics --grid)
 *   friction    the friction laws, sampled           (friction)
 *   spacetime   a simulation, psi(x, t)              (simulate)
 *   check       predicted speeds against simulation  (check)
 *   stability   spectra of front trains, per n; their
 *               boundaries and the (nu, S) diagram   (stability)
 *   figure      a gnuplot figure of one product      (gnuplot, plots/KIND.gp)
 *   sweep       a regime map over a grid of points,  (sweep; floquet --diagram
 *               with the Floquet boundaries           per gamma of thresholds)
 *   bench       work-precision timings               (bench)
 *
 * Each kind but figure is declared by its product in the catalogue
 * (catalog.h's bkf_catalog_kind), which is all the planner knows of it.
 * A key naming a file the product writes (BKF_OPT_PATH: simulate's
 * snapshots, a sweep's fields) names it inside the output folder; the plan
 * refuses anything else, "FILE:LINE: [KIND NAME]: KEY: ...", unless the
 * caller trusts the scene (bkf_scene_plan_options.trust); so it does a
 * figure's own `script =`, which gnuplot may turn into shell commands.
 *
 * The keys of each kind are in docs/scenes.md.  A key of a kind whose
 * product is in the catalogue (catalog.h) is checked at parse time by that
 * product's option table, the code that checks the command-line flag;
 * errors are one line "FILE:LINE: message".
 *
 * The plan is lazy: only what the scene's products ask for is computed (a
 * spacetime plot seeded with front n = 3 finds one root of n = 3; a speeds
 * table runs no simulation), and a computation two products need is done
 * once.  A step is a product of the catalogue with a list of key = value
 * texts and the file it writes. */
#ifndef BKFRONT_SCENE_H
#define BKFRONT_SCENE_H

#include <signal.h>
#include <stddef.h>
#include "bkfront/catalog.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

#define BKF_SCENE_NAME_LEN 64
#define BKF_SCENE_VALUE_LEN 256

typedef enum {
    BKF_SCENE_SPEEDS = 0,
    BKF_SCENE_PERIOD,
    BKF_SCENE_DISPERSION,
    BKF_SCENE_THRESHOLD,
    BKF_SCENE_BRANCH,
    BKF_SCENE_PROFILE,
    BKF_SCENE_VALIDITY,
    BKF_SCENE_FRICTION,
    BKF_SCENE_SPACETIME,
    BKF_SCENE_CHECK,
    BKF_SCENE_STABILITY,
    BKF_SCENE_FIGURE,
    BKF_SCENE_SWEEP,      /* after figure: the kinds before keep their numbers */
    BKF_SCENE_NKINDS
} bkf_scene_kind;

/* The kinds: those of the enum, then any a product of the catalogue
 * declares beyond them (catalog.h), numbered from BKF_SCENE_NKINDS on.
 * The name is NULL past bkf_scene_kind_count(). */
const char *bkf_scene_kind_name(bkf_scene_kind kind);
size_t bkf_scene_kind_count(void);

/* One key = value of a section, as written (checked at parse time). */
typedef struct {
    char key[32];
    char value[BKF_SCENE_VALUE_LEN];
    int line;
} bkf_scene_entry;

typedef struct {
    bkf_scene_kind kind;
    char name[BKF_SCENE_NAME_LEN];
    int line;                 /* of the section header */
    bkf_scene_entry *entries;
    size_t nentries;
} bkf_scene_product;

typedef struct {
    char *path;               /* as given; messages and relative scripts */
    bkf_scene_entry *model;   /* [model] and [accuracy] entries */
    size_t nmodel;
    bkf_scene_product *products;
    size_t nproducts;
    void *names_;             /* private: the products by name, for bkf_scene_find */
} bkf_scene;

/* BKF_EINPUT with "NAME:LINE: message" for syntax errors, unknown sections
 * or keys, bad values, duplicates, a missing required key (at the section's
 * header line) and figures whose data names no product; BKF_ENOMEM.
 * *out is NULL on failure. */
int bkf_scene_parse_file(const char *path, bkf_scene **out, bkf_error *err);
int bkf_scene_parse_string(const char *text, const char *name, bkf_scene **out, bkf_error *err);
void bkf_scene_free(bkf_scene *s);

/* The value of `key` for a product: its own, else [model]/[accuracy], else
 * NULL. */
const char *bkf_scene_value(const bkf_scene *s, const bkf_scene_product *p, const char *key);
const bkf_scene_product *bkf_scene_find(const bkf_scene *s, const char *name, int figures);

/* ------------------------------------------------------------------ plan */

typedef enum {
    BKF_SCENE_STEP_PRODUCT = 0, /* a product, by name, with key = value texts */
    BKF_SCENE_STEP_FIGURE = 1   /* one gnuplot run, every format */
} bkf_scene_step_kind;

/* One key = value text of a step; value NULL for a switch.  An output is a
 * file the step writes (out, spacetime): not part of what is computed. */
typedef struct {
    char *key;
    char *value;
    int output;
    int fixed;    /* a switch the kind always passes; a product without such a
                     key is not given it (--no-progress is the CLI's) */
} bkf_scene_arg;

typedef struct {
    bkf_scene_step_kind kind;
    const char *product;      /* "period", ...; "figure" */
    const bkf_catalog_entry *entry; /* NULL: not (yet) in the catalogue */
    bkf_scene_arg *args;      /* in the order of the equivalent command line */
    size_t nargs;
    char *output;             /* the file it writes (a figure: the first image) */
    size_t *users;            /* products that need it */
    size_t nusers;
    size_t data_product;      /* FIGURE: the product it shows (the first of
                                 data = A,B,...) */
    size_t *data_products;    /* FIGURE: every product it shows, in order */
    size_t ndata;
} bkf_scene_step;

typedef struct {
    size_t *steps;            /* its steps, in order */
    size_t nsteps;
} bkf_scene_product_plan;

typedef struct {
    bkf_scene_step *steps;    /* data steps first, figures last */
    size_t nsteps;
    bkf_scene_product_plan *products;  /* one per scene product */
    size_t nproducts;
    size_t deduplicated;      /* computations shared by two products */
    char *outdir;
    void *planner_;           /* private to bkf_scene_make_plan (NULL after it) */
} bkf_scene_plan;

typedef struct {
    const char *outdir;       /* required; files go there */
    unsigned formats;         /* figure formats when a figure sets none: bit 0 png,
                                 1 pdf, 2 svg; 0: png */
    int figures;              /* 0: leave figures out of the plan */
    int trust;                /* 1: a key naming a file (simulate's snapshots, a
                                 sweep's fields) may name it outside outdir, and a
                                 figure may run its own script =; 0: such a scene
                                 is refused with the key's line */
} bkf_scene_plan_options;

int bkf_scene_make_plan(const bkf_scene *s, const bkf_scene_plan_options *options,
                        bkf_scene_plan *plan, bkf_error *err);
void bkf_scene_plan_free(bkf_scene_plan *plan);

/* The step's equivalent command line without the program's name,
 * "period --mu 0.1:1e4:41 --log ... --out DIR/x.tsv", shell-quoted; a
 * figure is "gnuplot".  Caller frees; NULL when out of memory. */
char *bkf_scene_step_command(const bkf_scene_step *step);

/* The step's expected work in seconds of one core: its product's cost
 * hint (catalog.h) on the step's settings, 1 for a product without one, 0
 * for a figure (it waits for its data, then takes about a second).  A
 * guess, which orders the steps of a run with several jobs. */
double bkf_scene_step_cost(const bkf_scene_step *step);

/* The step as an argv vector: argv[0] the product, then --KEY [VALUE] in
 * order, NULL-terminated (caller frees with bkf_scene_argv_free). */
char **bkf_scene_step_argv(const bkf_scene_step *step, int *argc);
void bkf_scene_argv_free(char **argv);

/* ------------------------------------------------------------------- run */

struct bkf_scene_step_report; /* below */

typedef struct {
    /* Provenance of the tables: the program opening their first comment
     * (NULL: "libbkfront") and the text before the step's command in the
     * "command:" comment (NULL: none, e.g. "bkfront"). */
    const char *program;
    const char *command_prefix;
    const char *plots_dir;    /* the default scripts KIND.gp; required for figures */
    const char *scene_dir;    /* relative figure scripts; NULL: "." */
    bkf_catalog_hooks hooks;  /* handed to each product */
    /* Told the temporary file of each output while it is being written
     * (armed 1), and when it is gone (armed 0), so that a signal handler
     * may remove it; NULL: nobody is told. */
    void (*temp_file)(const char *path, int armed, void *data);
    void *data;               /* for temp_file and step_done */
    /* bkf_scene_run: how many steps at once (0 or 1: one after the other,
     * in the caller's thread).  Steps that do not need each other run on
     * their own threads; a figure starts once every step of its data is
     * done.  The files are those of a serial run, byte for byte. */
    unsigned jobs;
    /* bkf_scene_run: told of each step as it ends, one call at a time
     * (never two at once), in the order they end; NULL: nobody is told. */
    void (*step_done)(const struct bkf_scene_step_report *report, void *data);
} bkf_scene_run_options;

/* A step that ended.  A step stopped because hooks.cancel was raised is
 * BKF_ECANCELED, whatever it returned.  `warnings` are those its product
 * raised through hooks.warn (an under-resolved simulation, refused rows),
 * the first BKF_SCENE_WARNINGS of them; `nwarnings` counts them all. */
#define BKF_SCENE_WARNINGS 8
typedef struct bkf_scene_step_report {
    size_t step;
    int status;
    double seconds;              /* wall time of the step */
    const char *message;         /* why it failed ("" when it did not) */
    const char *gnuplot_warning; /* a figure's warning from gnuplot ("": none) */
    const char *const *warnings;
    size_t nwarnings;
} bkf_scene_step_report;

/* Carries out step `i` of the plan (data steps write their files
 * atomically; a figure runs gnuplot).  `done` holds the status of every
 * earlier step (NULL: all succeeded): a figure whose data failed is
 * skipped (BKF_ENUMERIC, "skipped: its data failed").  A warning gnuplot
 * printed goes to `warning` (may be NULL). */
int bkf_scene_run_step(const bkf_scene *s, const bkf_scene_plan *plan, size_t i,
                       const int *done, const bkf_scene_run_options *options, char *warning,
                       size_t wsize, bkf_error *err);

/* Carries out every step of the plan, options->jobs at a time, and writes
 * each step's status to status[i] (plan->nsteps entries; a step not run
 * because hooks.cancel was raised is BKF_ECANCELED and is not reported).
 * A failing step stops no other: the steps that do not need it still run,
 * figures of its data are skipped.  hooks.warn goes to the report of its
 * step, not to hooks.warn; hooks.progress and both temp_file callbacks are
 * called one at a time.  Returns BKF_OK when every step was run (each may
 * have failed), BKF_ECANCELED when the cancel flag left some unrun,
 * BKF_ENOMEM. */
int bkf_scene_run(const bkf_scene *s, const bkf_scene_plan *plan,
                  const bkf_scene_run_options *options, int *status, bkf_error *err);

/* The status of a run as a whole from its n steps' status[]: BKF_OK when
 * every step succeeded, else the gravest failure (out of memory, then a
 * cancellation, then bad input, then the first other one). */
int bkf_scene_run_status(const int *status, size_t n);

#ifdef __cplusplus
}
#endif

#endif
