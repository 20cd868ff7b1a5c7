/* The catalogue of products: every product bkfront computes, by name, with
 * its table of option keys and the calls that fill, check and write it.
 *
 * It is how scenes (and the command line) reach a product without knowing
 * it: make a spec (bkf_catalog_spec_new: the product's defaults), apply
 * key = value texts through the product's own option table
 * (bkf_catalog_apply: the validation every flag and scene key shares),
 * check the whole spec, write the table.  A product's numerics live in its
 * own module (period.h, profile.h, check.h, ...); an entry only adapts
 * them to one shape.  The library never prints and never exits. */
#ifndef BKFRONT_CATALOG_H
#define BKFRONT_CATALOG_H

#include <signal.h>
#include <stddef.h>
#include <stdio.h>
#include "bkfront/io.h"
#include "bkfront/options.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* What a long product may report and obey; every field may be NULL. */
typedef struct {
    int (*progress)(double fraction, void *data); /* fraction in [0, 1] */
    void (*warn)(const char *message, void *data); /* one line, kept going */
    void *data;
    const volatile sig_atomic_t *cancel;          /* raised: BKF_ECANCELED */
    /* Told each data file a product writes itself (beside its table) while
     * its temporary exists (armed 1) and when it is gone (armed 0), so that
     * a signal handler may remove it. */
    void (*temp_file)(const char *path, int armed, void *data);
    /* Stopped through cancel, a product replaces none of its own data
     * files unless this is set (its table is the caller's to keep or not). */
    int keep_canceled;
} bkf_catalog_hooks;

/* How a scene's section becomes computations of a product (scene.h): a
 * product gets a scene kind by declaring it here, in its catalogue entry,
 * and the flags of its option table (options.h) say the rest per key:
 * BKF_OPT_CLI_ONLY keys are not scene keys, the BKF_OPT_FANOUT key's list
 * is one step per value, a BKF_OPT_PATH key names a file inside the output
 * folder.
 *
 * A step passes, in this order: the switches of `first`; the keys of
 * `keys`; the section's other keys of the product's table, as written (the
 * kind's own product only); the switches of `last`; its files.  `keys` is
 * the order of the step's command line, items separated by spaces:
 *
 *   KEY             the section's value, if it sets one
 *   ^KEY            the section's, else [model]'s or [accuracy]'s (an
 *                   [accuracy] key reaches a product that has it only so)
 *   +KEY            the same, and one of them must set it
 *   ...=TEXT        ..., else TEXT (the scene's default, not the product's)
 *   ...=$OTHER      ..., else the scene's value of the key OTHER names
 *   KEY:=TEXT       always TEXT
 *   ...!TEXT        left out when it is TEXT (the default goes unsaid)
 *   ...?OTHER=TEXT  only when OTHER's value (own or inherited) is TEXT
 *   @KEY            the section's value, which names a key of the list
 *                   that is then left out (the parameter a branch varies)
 *
 * A value A:B:N of a key with BKF_OPT_LOG_SWITCH is geometric: its switch
 * follows it.  `outputs` is "KEY=SUFFIX ...": the files NAME + SUFFIX in
 * the output folder, the first the one figures show; with several steps
 * (a list of the fan-out key) NAME_1 + SUFFIX, NAME_2 + SUFFIX, ...; '#' in
 * SUFFIX is the step's number always.  NULL: "out=.tsv". */
typedef struct {
    const char *product;  /* NULL: the entry's own */
    const char *first, *keys, *last, *outputs;
    const char *fanout;   /* NULL: the table's BKF_OPT_FANOUT key; "LIST>KEY": the
                             section's key LIST (a scene key of the kind), one
                             step per value, passed as KEY */
} bkf_catalog_step;

typedef struct {
    const char *name;     /* the section's kind: [NAME] or [NAME LABEL] */
    bkf_catalog_step step;
    bkf_catalog_step also; /* product NULL: none; else steps of another product
                              the kind makes too (a sweep's Floquet boundaries) */
} bkf_catalog_kind;

typedef struct {
    const char *name;     /* "period": the subcommand and the key of a scene step */
    const char *summary;  /* one line */
    const char *usage;    /* the usage lines and description, before the options */
    const char *columns;  /* the columns and exit status, after the options */
    size_t spec_size;
    const bkf_option *(*options)(size_t *count);
    void (*init)(void *spec);                              /* the defaults */
    int (*check)(const void *spec, const char *prefix, bkf_error *err);
    int (*write)(const void *spec, FILE *out, bkf_io_format format,
                 const bkf_provenance *provenance, const bkf_catalog_hooks *hooks,
                 bkf_error *err);
    void (*release)(void *spec);                           /* frees lists; not the spec */
    const bkf_catalog_kind *kinds;                         /* its scene kinds */
    size_t nkinds;
    /* The expected work of writing `spec` (checked), in seconds of one core
     * at the rates of docs/benchmarks.md: a rough guess from the spec's
     * sizes, only to order a scene's steps when several run at once (the
     * longest first, so that it does not start last).  NULL: a second. */
    double (*cost)(const void *spec);
} bkf_catalog_entry;

size_t bkf_catalog_count(void);
const bkf_catalog_entry *bkf_catalog_at(size_t i);
/* NULL when there is no such product. */
const bkf_catalog_entry *bkf_catalog_find(const char *name);

/* A spec with the product's defaults (NULL with err: out of memory). */
void *bkf_catalog_spec_new(const bkf_catalog_entry *entry, bkf_error *err);
void bkf_catalog_spec_free(const bkf_catalog_entry *entry, void *spec);

/* key = text through the product's table; a switch takes NULL (or, from a
 * scene, "yes"/"no").  An unknown key is BKF_EINPUT naming the product. */
int bkf_catalog_apply(const bkf_catalog_entry *entry, void *spec, const char *key,
                      const char *text, const char *prefix, bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif
