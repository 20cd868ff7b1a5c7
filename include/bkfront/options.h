/* One table of option keys for every product: the same entry is the
 * command-line flag --NAME and the scene key NAME, so a value is validated by
 * one piece of code whichever way it arrives.
 *
 * A product publishes a spec struct and a table of bkf_option describing its
 * fields (offsetof).  bkf_option_apply parses one value's text into the
 * field, checking form and range; its messages read
 * "PREFIXNAME: what is wrong (valid form or range)", where the caller picks
 * the prefix: "--" on the command line, "" or "FILE:LINE: " in a scene.
 *
 * Lists have one grammar everywhere: V, V1,V2,... or A:B:N (N points from A
 * to B, both ends exact; N = 1 needs A == B), for numbers and for integers
 * (1:10:10 is 1, 2, ..., 10).  A geometric list (BKF_OPT_GEOMETRIC, or the
 * spec's switch at log_offset, the CLI's --log) spaces A:B:N geometrically
 * and needs every value > 0.  At most BKF_LIST_MAX values unless the entry
 * says fewer. */
#ifndef BKFRONT_OPTIONS_H
#define BKFRONT_OPTIONS_H

#include <stddef.h>
#include <stdint.h>
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A typo such as 1:2:1e9 should be an error, not an hour of work. */
#define BKF_LIST_MAX 1000000u

typedef enum {
    BKF_OPT_SWITCH,      /* int, set to 1; takes no value */
    BKF_OPT_DOUBLE,      /* double, finite decimal, in [min, max] if bounded */
    BKF_OPT_COUNT,       /* size_t, decimal digits, in [min, max] (min 1, max SIZE_MAX by default) */
    BKF_OPT_DOUBLE_LIST, /* bkf_list */
    BKF_OPT_COUNT_LIST,  /* bkf_list of integral values, in [min, max] as for a count */
    BKF_OPT_CHOICE,      /* int, the index in choices */
    BKF_OPT_TEXT,        /* const char *, the text itself (not copied), non-empty */
    BKF_OPT_SEED,        /* uint64_t, decimal digits, 0 allowed */
    BKF_OPT_CUSTOM       /* set() does everything */
} bkf_option_type;

enum {
    BKF_OPT_MIN = 1u << 0,       /* min applies */
    BKF_OPT_MAX = 1u << 1,       /* max applies */
    BKF_OPT_MIN_OPEN = 1u << 2,  /* (min, ...: min itself is out */
    BKF_OPT_MAX_OPEN = 1u << 3,  /* ..., max): max itself is out */
    BKF_OPT_GEOMETRIC = 1u << 4, /* a list whose A:B:N is always geometric */
    BKF_OPT_LOG_SWITCH = 1u << 5,/* geometric when the int at log_offset is set */
    BKF_OPT_REQUIRED = 1u << 6,  /* the caller reports it missing ("--mu is required") */
    BKF_OPT_CLI_ONLY = 1u << 7,  /* a flag with no scene key (--out, --help) */
    BKF_OPT_SCENE_ONLY = 1u << 8,/* a scene key with no flag */
    BKF_OPT_RUN_FILE = 1u << 9,  /* a data file of one run (simulate's spacetime and
                                    snapshots): not a key of a sweep, whose points
                                    keep their fields by --fields */
    /* What a scene does with the key (catalog.h's scene kinds): */
    BKF_OPT_FANOUT = 1u << 10,   /* a list in a scene is one step per value, each
                                    with its own file (nu = -0.90,-0.92: two runs) */
    BKF_OPT_PATH = 1u << 11      /* names a file or folder the product writes: in a
                                    scene, inside the output folder (or refused) */
};

/* A list of values: V (count 1), V1,V2,... or A:B:N.  from and to are the
 * first and last values; is_range is set for A:B:N and for comma lists. */
typedef struct {
    double *values; /* owned; free with bkf_list_free */
    size_t count;
    double from, to;
    int is_range;
} bkf_list;

typedef struct bkf_option {
    const char *name;          /* "mu": flag --mu, scene key mu */
    bkf_option_type type;
    size_t offset;             /* of the field in the spec (offsetof) */
    unsigned flags;            /* BKF_OPT_* */
    double min, max;           /* with BKF_OPT_MIN / BKF_OPT_MAX */
    const char *const *choices;/* BKF_OPT_CHOICE: NULL-terminated */
    size_t max_count;          /* lists: at most this many values; 0 = BKF_LIST_MAX */
    size_t log_offset;         /* BKF_OPT_LOG_SWITCH: the int switch's offset */
    int (*set)(void *spec, const char *text, bkf_error *err); /* BKF_OPT_CUSTOM;
                                  messages without the "PREFIXNAME: " part */
    const char *form;          /* the value's form in usage: "M", "LIST" */
    const char *shown_default; /* the default as help shows it, or NULL */
    const char *help;          /* help text; '\n' starts a new help line */
} bkf_option;

/* Parses `text` into the field of `spec` that `opt` describes.  A switch
 * takes text NULL.  On error the field is unchanged and err reads
 * "PREFIXNAME: ...".  BKF_EINPUT, or BKF_ENOMEM for a list. */
int bkf_option_apply(const bkf_option *opt, void *spec, const char *text, const char *prefix,
                     bkf_error *err);

/* Where a product's table came from, for its comment lines: `program`
 * opens the first comment ("bkfront 0.1.0" gives "bkfront 0.1.0 period: ...";
 * NULL gives "libbkfront"), `command` (NULL: none) is written as the last
 * comment, "command: COMMAND". */
typedef struct {
    const char *program;
    const char *command;
} bkf_provenance;

/* The entry called `name` in a table of n, or NULL. */
const bkf_option *bkf_option_find(const bkf_option *table, size_t n, const char *name);

/* The valid form and range in words, as in messages ("a number in (-1, 1)",
 * "tsv or json"), into buf.  Returns buf. */
const char *bkf_option_describe(const bkf_option *opt, char *buf, size_t size);

/* Frees every list field of `spec` that the table describes. */
void bkf_option_free_lists(const bkf_option *table, size_t n, void *spec);

/* The list grammar on its own: name and prefix only for messages; max 0
 * means BKF_LIST_MAX.  On error *list is empty (values NULL). */
int bkf_list_parse(const char *text, int geometric, int integer, size_t max, const char *prefix,
                   const char *name, bkf_list *list, bkf_error *err);
void bkf_list_free(bkf_list *list);

/* A finite decimal number, the whole string: digits, sign, point, exponent;
 * no space, hex, nan or inf, no overflow (underflow gives 0 or a subnormal). */
int bkf_option_parse_double(const char *text, const char *prefix, const char *name,
                            double *value, bkf_error *err);

/* A decimal integer in [min, max], digits only. */
int bkf_option_parse_count(const char *text, size_t min, size_t max, const char *prefix,
                           const char *name, size_t *value, bkf_error *err);

/* One of `choices` (NULL-terminated). */
int bkf_option_parse_choice(const char *text, const char *const *choices, const char *prefix,
                            const char *name, int *index, bkf_error *err);

/* The shortest "%.Ng" (N = 1..17) of x that reads back as x bit for bit:
 * 0.3 is "0.3", not 0.29999999999999999.  NaN is "nan", infinities
 * "inf"/"-inf".  Returns buf (size >= 32 always suffices). */
const char *bkf_format_number(double x, char *buf, size_t size);

/* User text inside a one-line message: control characters become '?', text
 * longer than about size - 4 is cut with "...".  Returns buf. */
const char *bkf_option_shown(const char *text, char *buf, size_t size);

#ifdef __cplusplus
}
#endif

#endif
