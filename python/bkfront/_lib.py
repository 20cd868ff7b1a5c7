"""The C library through cffi's ABI mode: no compiler at import, only
libbkfront.so.MAJOR and the declarations below.

The declarations copy the public headers (include/bkfront/) for the few
structs Python fills or reads; everything else is reached through the
catalogue (catalog.h), whose products take key = value texts, as the CLI's
flags and the scene keys do, and write the CLI's own tables."""

import os

import cffi

MAJOR = 0

CDEF = """
typedef struct _IO_FILE FILE;
FILE *open_memstream(char **ptr, size_t *sizeloc);
int fclose(FILE *stream);
void free(void *ptr);

/* status.h */
typedef struct { char message[320]; int status; } bkf_error;
const char *bkf_status_name(int status);
int bkf_status_is_numerical(int status);
/* version.h */
const char *bkf_version(void);

/* cycle.h */
typedef struct { double tol; int stepper; int warm_start; } bkf_cycle_options;
bkf_cycle_options bkf_cycle_options_default(void);
typedef struct {
    double mu, nu, period, period_err, xmax, xmin, multiplier, log_multiplier,
           log_multiplier_err, return_map_slope, section_y, section_slope;
    size_t steps, rhs_calls, jacobian_calls, newton_iterations;
    const char *stepper;
    const char *model;
} bkf_cycle_result;
typedef struct bkf_cycle bkf_cycle;
bkf_cycle *bkf_cycle_alloc(void);
void bkf_cycle_free(bkf_cycle *cycle);
int bkf_cycle_estimate(bkf_cycle *cycle, double mu, double nu,
                       const bkf_cycle_options *options, int method,
                       bkf_cycle_result *out, bkf_error *err);

/* options.h */
typedef struct bkf_option {
    const char *name;
    int type;
    size_t offset;
    unsigned flags;
    double min, max;
    const char *const *choices;
    size_t max_count;
    size_t log_offset;
    int (*set)(void *spec, const char *text, bkf_error *err);
    const char *form;
    const char *shown_default;
    const char *help;
} bkf_option;
typedef struct { const char *program; const char *command; } bkf_provenance;

/* catalog.h */
typedef struct {
    int (*progress)(double fraction, void *data);
    void (*warn)(const char *message, void *data);
    void *data;
    const int *cancel;
    void (*temp_file)(const char *path, int armed, void *data);
    int keep_canceled;
} bkf_catalog_hooks;
typedef struct {
    const char *name;
    const char *summary;
    const char *usage;
    const char *columns;
    size_t spec_size;
    const bkf_option *(*options)(size_t *count);
    void (*init)(void *spec);
    int (*check)(const void *spec, const char *prefix, bkf_error *err);
    int (*write)(const void *spec, FILE *out, int format, const bkf_provenance *provenance,
                 const bkf_catalog_hooks *hooks, bkf_error *err);
    void (*release)(void *spec);
    const void *kinds;
    size_t nkinds;
    double (*cost)(const void *spec);
} bkf_catalog_entry;
size_t bkf_catalog_count(void);
const bkf_catalog_entry *bkf_catalog_at(size_t i);
const bkf_catalog_entry *bkf_catalog_find(const char *name);
void *bkf_catalog_spec_new(const bkf_catalog_entry *entry, bkf_error *err);
void bkf_catalog_spec_free(const bkf_catalog_entry *entry, void *spec);
int bkf_catalog_apply(const bkf_catalog_entry *entry, void *spec, const char *key,
                      const char *text, const char *prefix, bkf_error *err);
"""

# bkf_status (status.h), bkf_option_type (options.h), bkf_io_format (io.h)
OK, ENUMERIC, EINPUT, ENOMEM, ECANCELED, ETOL, EBUDGET, EBLOWUP, EIO = range(9)
OPT_SWITCH = 0
OPT_REQUIRED = 1 << 6
OPT_CLI_ONLY = 1 << 7
OPT_SCENE_ONLY = 1 << 8
IO_JSON = 1


def library_path():
    """Where libbkfront.so.MAJOR is: $BKFRONT_LIBRARY, else the one make
    install put beside this package (_paths.py), else this source tree's
    build/, else the dynamic loader's search."""
    env = os.environ.get("BKFRONT_LIBRARY")
    if env:
        return env
    here = os.path.dirname(os.path.abspath(__file__))
    try:
        from . import _paths
        return os.path.normpath(os.path.join(here, _paths.LIBRARY))
    except ImportError:
        pass
    built = os.path.join(here, "..", "..", "build", "libbkfront.so.%d" % MAJOR)
    if os.path.exists(built):
        return os.path.normpath(built)
    return "libbkfront.so.%d" % MAJOR


ffi = cffi.FFI()
ffi.cdef(CDEF)
try:
    lib = ffi.dlopen(library_path())
except OSError as exc:
    raise ImportError("bkfront: cannot load the C library %s (%s); set BKFRONT_LIBRARY "
                      "to the path of libbkfront.so.%d" % (library_path(), exc, MAJOR)) from exc
libc = ffi.dlopen(None)
