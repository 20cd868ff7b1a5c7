/* Scenes: what a user wants computed, as an INI file, and the lazy plan.
 *
 * A scene has a [model] section (gamma, c, nu, S, model), an optional
 * [accuracy] section (tol, N) and one section per product, [KIND] or
 * [KIND NAME]:
 *
 *   speeds      table of allowed front speeds        (bkfront speeds)
 *   period      T(mu) beside its asymptotics, per nu (bkfront period)
 *   dispersion  Floquet dispersion relations, per nu (bkfront floquet)
 *   threshold   stability threshold nu_pd, or its curve (bkfront floquet --threshold)
 *   branch      speed branches by continuation, per n (bkfront branch)
 *   profile     front profiles f(z), f'(z), per n    (bkfront profile)
 *   validity    errors of the asymptotics on a grid  (bkfront asymptotics --grid)
 *   friction    the friction laws, sampled           (closed forms)
 *   spacetime   a simulation, psi(x, t)              (bkfront simulate)
 *   check       predicted speeds against simulation  (bkfront check)
 *   figure      a gnuplot figure of one product      (gnuplot, plots/KIND.gp)
 *
 * The keys of each kind are in docs/scenes.md.  Parsing (libinih)
 * checks every key's value with the same rules as the matching command-line
 * flag; errors are one line "FILE:LINE: message".
 *
 * A product is carried out by the subcommand named above, run in-process
 * with the product's settings (so a scene and the command line can never
 * disagree); the plan is the list of those runs.  It is lazy: only what the
 * scene's products ask for is run (a spacetime plot seeded with front n = 3
 * makes the speeds solver find one root of n = 3; a speeds table runs no
 * simulation), and a computation two products need is run once. */
#ifndef BKFRONT_CLI_SCENE_H
#define BKFRONT_CLI_SCENE_H

#include <stddef.h>
#include "bkfront/status.h"

#define SCENE_NAME_LEN 64
#define SCENE_VALUE_LEN 256

typedef enum {
    SCENE_SPEEDS = 0,
    SCENE_PERIOD,
    SCENE_DISPERSION,
    SCENE_THRESHOLD,
    SCENE_BRANCH,
    SCENE_PROFILE,
    SCENE_VALIDITY,
    SCENE_FRICTION,
    SCENE_SPACETIME,
    SCENE_CHECK,
    SCENE_FIGURE,
    SCENE_NKINDS
} scene_kind;

const char *scene_kind_name(scene_kind kind);

/* One key = value of a section, as written (checked at parse time). */
typedef struct {
    char key[32];
    char value[SCENE_VALUE_LEN];
    int line;
} scene_entry;

typedef struct {
    scene_kind kind;
    char name[SCENE_NAME_LEN];
    int line;                 /* of the section header */
    scene_entry *entries;
    size_t nentries;
} scene_product;

typedef struct {
    char *path;               /* as given; messages and relative scripts */
    scene_entry *model;       /* [model] and [accuracy] entries */
    size_t nmodel;
    scene_product *products;
    size_t nproducts;
} scene;

/* BKF_EINPUT with "NAME:LINE: message" for syntax errors, unknown sections
 * or keys, bad values, duplicates, a missing required key (at the section's
 * header line) and figures whose data names no product; BKF_ENOMEM.
 * *out is NULL on failure. */
int scene_parse_file(const char *path, scene **out, bkf_error *err);
int scene_parse_string(const char *text, const char *name, scene **out, bkf_error *err);
void scene_free(scene *s);

/* The value of `key` for a product: its own, else [model]/[accuracy], else
 * NULL. */
const char *scene_value(const scene *s, const scene_product *p, const char *key);
const scene_product *scene_find(const scene *s, const char *name, int figures);

/* A checked list value ("a,b,c" or "A:B:N") as separate texts; 0 when out
 * of memory. */
int scene_list_values(const char *text, char ***items, size_t *count);
void scene_list_free(char **items, size_t count);

/* ------------------------------------------------------------------ plan */

typedef enum {
    STEP_COMMAND = 0,  /* a bkfront subcommand, in-process */
    STEP_FORMULA = 1,  /* closed forms sampled into a table */
    STEP_FIGURE = 2    /* one gnuplot run, every format */
} step_kind;

typedef struct {
    step_kind kind;
    char **argv;              /* COMMAND: argv[0] is the subcommand; NULL-terminated */
    int argc;
    char *output;             /* the file it writes (a figure: the first image) */
    size_t *users;            /* products that need it */
    size_t nusers;
    size_t data_product;      /* FIGURE: the product it shows */
} scene_step;

typedef struct {
    size_t *steps;            /* its steps, in order */
    size_t nsteps;
} scene_product_plan;

typedef struct {
    scene_step *steps;        /* data steps first, figures last */
    size_t nsteps;
    scene_product_plan *products;  /* one per scene product */
    size_t nproducts;
    size_t deduplicated;      /* computations shared by two products */
    char *outdir;
} scene_plan;

typedef struct {
    const char *outdir;       /* required; files go there */
    unsigned formats;         /* figure formats when a figure sets none: bit 0 png,
                                 1 pdf, 2 svg; 0: png */
    int figures;              /* 0: leave figures out of the plan */
} scene_plan_options;

int scene_make_plan(const scene *s, const scene_plan_options *options, scene_plan *plan,
                    bkf_error *err);
void scene_plan_free(scene_plan *plan);

/* "speeds", "period", ..., "friction", "figure": the subcommand or kind. */
const char *scene_step_label(const scene_step *step);
/* The step's command line, shell-quoted (caller frees). */
char *scene_step_command(const scene_step *step);

#endif
