/* The catalogue (catalog.h): one adapter per product, in the order the CLI
 * lists them. */
#include "bkfront/catalog.h"

#include <stdlib.h>
#include <string.h>

#include "bkfront/check.h"
#include "bkfront/period.h"
#include "bkfront/profile.h"

/* ------------------------------------------------------------- period */

static const bkf_option *period_options(size_t *count)
{
    *count = bkf_period_noptions;
    return bkf_period_options;
}
static void period_init(void *spec) { *(bkf_period_spec *)spec = bkf_period_spec_default(); }
static int period_check(const void *spec, const char *prefix, bkf_error *err)
{
    return bkf_period_check(spec, prefix, err);
}
static int period_write(const void *spec, FILE *out, bkf_io_format format,
                        const bkf_provenance *prov, const bkf_catalog_hooks *hooks,
                        bkf_error *err)
{
    (void)hooks;
    return bkf_period_write(spec, out, format, prov, err);
}
static void period_release(void *spec) { bkf_period_spec_free(spec); }

/* ------------------------------------------------------------ profile */

static const bkf_option *profile_options(size_t *count)
{
    *count = bkf_profile_noptions;
    return bkf_profile_options;
}
static void profile_init(void *spec) { *(bkf_profile_spec *)spec = bkf_profile_spec_default(); }
static int profile_check(const void *spec, const char *prefix, bkf_error *err)
{
    return bkf_profile_check(spec, prefix, err);
}
static int profile_write(const void *spec, FILE *out, bkf_io_format format,
                         const bkf_provenance *prov, const bkf_catalog_hooks *hooks,
                         bkf_error *err)
{
    (void)hooks;
    return bkf_profile_write(spec, out, format, prov, err);
}
static void profile_release(void *spec) { bkf_profile_spec_free(spec); }

/* -------------------------------------------------------------- check */

static const bkf_option *check_options(size_t *count)
{
    *count = bkf_check_nkeys;
    return bkf_check_keys;
}
static void check_init(void *spec) { *(bkf_check_spec *)spec = bkf_check_spec_default(); }
static int check_check(const void *spec, const char *prefix, bkf_error *err)
{
    return bkf_check_spec_check(spec, prefix, err);
}
/* The catalogue's progress may answer; the check stops by cancel only. */
static void check_progress(double fraction, void *data)
{
    const bkf_catalog_hooks *h = data;
    h->progress(fraction, h->data);
}
static void check_warning(const char *message, void *data)
{
    const bkf_catalog_hooks *h = data;
    h->warn(message, h->data);
}
/* A stable front that disagrees is BKF_ENUMERIC after the whole table. */
static int check_write(const void *spec, FILE *out, bkf_io_format format,
                       const bkf_provenance *prov, const bkf_catalog_hooks *hooks,
                       bkf_error *err)
{
    bkf_catalog_hooks copy = {0};
    if (hooks) copy = *hooks;
    bkf_check_hooks h = {.progress = copy.progress ? check_progress : NULL,
                         .warning = copy.warn ? check_warning : NULL,
                         .data = &copy,
                         .cancel = copy.cancel};
    return bkf_check_write(spec, out, format, prov, &h, NULL, err);
}
static void check_release(void *spec)
{
    bkf_option_free_lists(bkf_check_keys, bkf_check_nkeys, spec);
}

/* ---------------------------------------------------------- the table */

static const bkf_catalog_entry entries[] = {
    {"period", "period T(mu, nu) of the reduced front equation, at points, on grids or branches",
     NULL, NULL, sizeof(bkf_period_spec), period_options, period_init, period_check,
     period_write, period_release},
    {"profile", "front profiles f(z), f'(z) and their place x along the system",
     NULL, NULL, sizeof(bkf_profile_spec), profile_options, profile_init, profile_check,
     profile_write, profile_release},
    {"check", "predicted front speeds against seeded simulations: agreement and stability per n",
     NULL, NULL, sizeof(bkf_check_spec), check_options, check_init, check_check, check_write,
     check_release},
};
#define NENTRIES (sizeof entries / sizeof entries[0])

size_t bkf_catalog_count(void) { return NENTRIES; }

const bkf_catalog_entry *bkf_catalog_at(size_t i) { return i < NENTRIES ? &entries[i] : NULL; }

const bkf_catalog_entry *bkf_catalog_find(const char *name)
{
    for (size_t i = 0; name && i < NENTRIES; i++)
        if (strcmp(entries[i].name, name) == 0) return &entries[i];
    return NULL;
}

void *bkf_catalog_spec_new(const bkf_catalog_entry *entry, bkf_error *err)
{
    if (!entry) {
        bkf_error_set(err, BKF_EINPUT, "no product given");
        return NULL;
    }
    void *spec = calloc(1, entry->spec_size);
    if (!spec) {
        bkf_error_set(err, BKF_ENOMEM, "out of memory");
        return NULL;
    }
    entry->init(spec);
    return spec;
}

void bkf_catalog_spec_free(const bkf_catalog_entry *entry, void *spec)
{
    if (!entry || !spec) return;
    entry->release(spec);
    free(spec);
}

int bkf_catalog_apply(const bkf_catalog_entry *entry, void *spec, const char *key,
                      const char *text, const char *prefix, bkf_error *err)
{
    if (!entry || !spec || !key)
        return bkf_error_set(err, BKF_EINPUT, "no product, spec or key given");
    size_t n;
    const bkf_option *table = entry->options(&n);
    const bkf_option *opt = bkf_option_find(table, n, key);
    char shown[80];
    if (!opt || (opt->flags & BKF_OPT_CLI_ONLY))
        return bkf_error_set(err, BKF_EINPUT, "%s%s: not a key of %s",
                             prefix ? prefix : "", bkf_option_shown(key, shown, sizeof shown),
                             entry->name);
    if (opt->type == BKF_OPT_SWITCH && text) {
        /* A scene writes a switch as key = yes or no. */
        if (strcmp(text, "no") == 0) return BKF_OK;
        if (strcmp(text, "yes") != 0)
            return bkf_error_set(err, BKF_EINPUT, "%s%s: '%s' is not yes or no",
                                 prefix ? prefix : "", opt->name,
                                 bkf_option_shown(text, shown, sizeof shown));
        text = NULL;
    }
    return bkf_option_apply(opt, spec, text, prefix ? prefix : "", err);
}
