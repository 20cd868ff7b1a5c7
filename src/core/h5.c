/* HDF5 fields on a grid (h5.h). */
#define _POSIX_C_SOURCE 200809L
#include "bkfront/h5.h"
#include "lazylib_internal.h"

#include <errno.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>

#include <hdf5.h>
#include <hdf5_hl.h>

/* HDF5 is loaded at the first write, not linked: its dependency tree
 * (libcurl, gnutls, krb5, ldap, ...) took two thirds of every bkfront
 * process's start, HDF5 file or not.  The headers give the types and
 * signatures; the sonames are those of the libraries the headers belong to
 * (the Makefile reads them off the development files), so the loaded ABI is
 * the compiled one, and the version is checked once more after loading. */
#ifndef BKF_HDF5_SONAME
#error "BKF_HDF5_SONAME (the soname of libhdf5, e.g. libhdf5_serial.so.103) is set by the Makefile"
#endif
#ifndef BKF_HDF5_HL_SONAME
#error "BKF_HDF5_HL_SONAME (the soname of libhdf5_hl) is set by the Makefile"
#endif

/* The functions called, from libhdf5 then (H5DS) libhdf5_hl. */
#define H5_FUNCTIONS(X)                                                                      \
    X(H5open) X(H5get_libversion) X(H5Aclose) X(H5Acreate2) X(H5Awrite) X(H5Dclose)          \
    X(H5Dcreate2) X(H5Dwrite) X(H5Eget_auto2) X(H5Eset_auto2) X(H5Ewalk2) X(H5Fclose)       \
    X(H5Fcreate) X(H5Fflush) X(H5Fget_file_image) X(H5Pclose) X(H5Pcreate) X(H5Pset_chunk)  \
    X(H5Pset_deflate) X(H5Pset_fapl_core) X(H5Pset_fclose_degree) X(H5Pset_obj_track_times)   \
    X(H5Pset_shuffle) X(H5Sclose) X(H5Screate) X(H5Screate_simple) X(H5Tclose) X(H5Tcopy)    \
    X(H5Tset_cset) X(H5Tset_size) X(H5Zfilter_avail)
#define H5_HL_FUNCTIONS(X) X(H5DSattach_scale) X(H5DSset_label) X(H5DSset_scale)
/* The library's predefined types and property classes: variables, valid
 * after H5open (what the header's H5T_NATIVE_DOUBLE etc. expand to). */
#define H5_IDS(X)                                                                            \
    X(H5T_C_S1_g) X(H5T_STD_I64LE_g) X(H5T_IEEE_F64LE_g) X(H5T_IEEE_F32LE_g)                 \
    X(H5T_NATIVE_LLONG_g) X(H5T_NATIVE_DOUBLE_g) X(H5T_NATIVE_FLOAT_g)                       \
    X(H5P_CLS_DATASET_CREATE_ID_g) X(H5P_CLS_FILE_ACCESS_ID_g) X(H5P_CLS_FILE_CREATE_ID_g)

#define H5_POINTER(f) __typeof__(f) *f;
#define H5_ID(v) hid_t v;
static struct {
    H5_FUNCTIONS(H5_POINTER)
    H5_HL_FUNCTIONS(H5_POINTER)
    H5_IDS(H5_ID)
} h5;

/* The header's flag macros (H5F_ACC_TRUNC) call H5check and H5open, which
 * are not linked: the loader has called H5open, the version is checked. */
#undef H5CHECK
#define H5CHECK
#undef H5OPEN
#define H5OPEN

/* Chunks of about 1 MiB of float32: what HDF5's default chunk cache holds,
 * and a row at a time for very wide grids. */
#define CHUNK_VALUES 262144u

/* The innermost description on HDF5's error stack: the cause, not the
 * chain of callers that passed it on. */
static herr_t first_description(unsigned n, const H5E_error2_t *e, void *data)
{
    char *buf = data;
    if (n == 0 && e->desc && *e->desc) snprintf(buf, 160, "%s (%s)", e->desc, e->func_name);
    return 0;
}

typedef struct {
    hid_t file, scale[2];
    const char *step; /* the failed call, for the message */
    char cause[160];
} writer;

/* Records the first failure: `ok` false means the call named `step` failed. */
static int check(writer *w, int ok, const char *step)
{
    if (ok || w->step) return ok;
    w->step = step;
    w->cause[0] = '\0';
    h5.H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, first_description, w->cause);
    return 0;
}

static int attribute(writer *w, hid_t on, const bkf_h5_attribute *a)
{
    hid_t space = h5.H5Screate(H5S_SCALAR), type = -1, attr = -1;
    int ok = check(w, space >= 0, "H5Screate");
    if (ok && a->kind == BKF_H5_TEXT) {
        type = h5.H5Tcopy(h5.H5T_C_S1_g);
        ok = check(w, type >= 0, "H5Tcopy") &&
             check(w, h5.H5Tset_size(type, H5T_VARIABLE) >= 0, "H5Tset_size") &&
             check(w, h5.H5Tset_cset(type, H5T_CSET_UTF8) >= 0, "H5Tset_cset");
    }
    hid_t file_type = a->kind == BKF_H5_TEXT  ? type
                      : a->kind == BKF_H5_INT ? h5.H5T_STD_I64LE_g
                                              : h5.H5T_IEEE_F64LE_g;
    if (ok) ok = check(w, (attr = h5.H5Acreate2(on, a->name, file_type, space, H5P_DEFAULT,
                                             H5P_DEFAULT)) >= 0, "H5Acreate2");
    if (ok) {
        long long i = a->integer;
        const char *text = a->text ? a->text : "";
        herr_t r = a->kind == BKF_H5_TEXT  ? h5.H5Awrite(attr, type, &text)
                   : a->kind == BKF_H5_INT ? h5.H5Awrite(attr, h5.H5T_NATIVE_LLONG_g, &i)
                                           : h5.H5Awrite(attr, h5.H5T_NATIVE_DOUBLE_g, &a->number);
        ok = check(w, r >= 0, "H5Awrite");
    }
    if (attr >= 0) ok = check(w, h5.H5Aclose(attr) >= 0, "H5Aclose") && ok;
    if (type >= 0) ok = check(w, h5.H5Tclose(type) >= 0, "H5Tclose") && ok;
    if (space >= 0) ok = check(w, h5.H5Sclose(space) >= 0, "H5Sclose") && ok;
    return ok;
}

static int long_name(writer *w, hid_t on, const char *text)
{
    if (!text) return 1;
    bkf_h5_attribute a = {.name = "long_name", .kind = BKF_H5_TEXT, .text = text};
    return attribute(w, on, &a);
}

static int axis(writer *w, int k, const bkf_h5_axis *ax)
{
    hsize_t n = ax->count;
    hid_t space = h5.H5Screate_simple(1, &n, NULL), dcpl = h5.H5Pcreate(h5.H5P_CLS_DATASET_CREATE_ID_g), d = -1;
    int ok = check(w, space >= 0, "H5Screate_simple") && check(w, dcpl >= 0, "H5Pcreate") &&
             check(w, h5.H5Pset_obj_track_times(dcpl, 0) >= 0, "H5Pset_obj_track_times");
    if (ok) ok = check(w, (d = h5.H5Dcreate2(w->file, ax->name, h5.H5T_IEEE_F64LE_g, space, H5P_DEFAULT,
                                          dcpl, H5P_DEFAULT)) >= 0, "H5Dcreate2");
    if (dcpl >= 0) ok = check(w, h5.H5Pclose(dcpl) >= 0, "H5Pclose") && ok;
    if (ok && n)
        ok = check(w, h5.H5Dwrite(d, h5.H5T_NATIVE_DOUBLE_g, H5S_ALL, H5S_ALL, H5P_DEFAULT,
                               ax->values) >= 0, "H5Dwrite");
    if (ok) ok = check(w, h5.H5DSset_scale(d, ax->name) >= 0, "H5DSset_scale");
    if (ok) ok = long_name(w, d, ax->long_name);
    if (space >= 0) ok = check(w, h5.H5Sclose(space) >= 0, "H5Sclose") && ok;
    w->scale[k] = d; /* closed with the file */
    return ok;
}

static int field(writer *w, const bkf_h5_grid *g, const bkf_h5_field *f)
{
    hsize_t dims[2] = {g->rows.count, g->columns.count};
    hsize_t chunk[2];
    chunk[1] = dims[1] < CHUNK_VALUES ? dims[1] : CHUNK_VALUES;
    chunk[0] = CHUNK_VALUES / chunk[1];
    if (chunk[0] > dims[0]) chunk[0] = dims[0];
    hid_t space = h5.H5Screate_simple(2, dims, NULL), dcpl = h5.H5Pcreate(h5.H5P_CLS_DATASET_CREATE_ID_g), d = -1;
    int ok = check(w, space >= 0, "H5Screate_simple") && check(w, dcpl >= 0, "H5Pcreate") &&
             check(w, h5.H5Pset_obj_track_times(dcpl, 0) >= 0, "H5Pset_obj_track_times");
    /* a chunk may not be empty: a grid without rows has no chunks */
    if (ok && dims[0] && dims[1]) {
        ok = check(w, h5.H5Pset_chunk(dcpl, 2, chunk) >= 0, "H5Pset_chunk");
        if (ok && g->deflate)
            ok = check(w, h5.H5Zfilter_avail(H5Z_FILTER_DEFLATE) > 0, "h5.H5Zfilter_avail(deflate)") &&
                 check(w, h5.H5Pset_shuffle(dcpl) >= 0, "H5Pset_shuffle") &&
                 check(w, h5.H5Pset_deflate(dcpl, g->deflate) >= 0, "H5Pset_deflate");
    }
    if (ok) ok = check(w, (d = h5.H5Dcreate2(w->file, f->name, h5.H5T_IEEE_F32LE_g, space, H5P_DEFAULT,
                                          dcpl, H5P_DEFAULT)) >= 0, "H5Dcreate2");
    if (ok && dims[0] && dims[1])
        ok = check(w, h5.H5Dwrite(d, h5.H5T_NATIVE_FLOAT_g, H5S_ALL, H5S_ALL, H5P_DEFAULT,
                               f->values) >= 0, "H5Dwrite");
    for (unsigned k = 0; ok && k < 2; k++)
        ok = check(w, h5.H5DSattach_scale(d, w->scale[k], k) >= 0, "H5DSattach_scale") &&
             check(w, h5.H5DSset_label(d, k, k ? g->columns.name : g->rows.name) >= 0,
                   "H5DSset_label");
    if (ok) ok = long_name(w, d, f->long_name);
    if (d >= 0) ok = check(w, h5.H5Dclose(d) >= 0, "H5Dclose") && ok;
    if (dcpl >= 0) ok = check(w, h5.H5Pclose(dcpl) >= 0, "H5Pclose") && ok;
    if (space >= 0) ok = check(w, h5.H5Sclose(space) >= 0, "H5Sclose") && ok;
    return ok;
}

static int valid_name(const char *name)
{
    return name && *name && !strchr(name, '/') && strcmp(name, ".") != 0;
}

static int check_grid(const bkf_h5_grid *g, bkf_error *err)
{
    if (!g || !g->nfields || !g->fields)
        return bkf_error_set(err, BKF_EINPUT, "HDF5 grid: no fields to write");
    if (g->deflate > BKF_H5_DEFLATE_MAX)
        return bkf_error_set(err, BKF_EINPUT, "HDF5 grid: deflate %u is not in [0, %d]",
                             g->deflate, BKF_H5_DEFLATE_MAX);
    const bkf_h5_axis *ax[2] = {&g->rows, &g->columns};
    const char *names[64];
    size_t n = 0;
    for (int k = 0; k < 2; k++) {
        if (!valid_name(ax[k]->name) || (ax[k]->count && !ax[k]->values))
            return bkf_error_set(err, BKF_EINPUT, "HDF5 grid: axis %d needs a name without '/' "
                                 "and its values", k);
        names[n++] = ax[k]->name;
    }
    if (g->nfields > 62) return bkf_error_set(err, BKF_EINPUT, "HDF5 grid: at most 62 fields");
    for (size_t i = 0; i < g->nfields; i++) {
        const bkf_h5_field *f = &g->fields[i];
        if (!valid_name(f->name) ||
            (g->rows.count && g->columns.count && !f->values))
            return bkf_error_set(err, BKF_EINPUT, "HDF5 grid: field %zu needs a name without '/' "
                                 "and its values", i);
        names[n++] = f->name;
    }
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j < i; j++)
            if (strcmp(names[i], names[j]) == 0)
                return bkf_error_set(err, BKF_EINPUT, "HDF5 grid: the name '%s' is given twice",
                                     names[i]);
    for (size_t i = 0; i < g->nattributes; i++)
        if (!g->attributes || !g->attributes[i].name || !*g->attributes[i].name)
            return bkf_error_set(err, BKF_EINPUT, "HDF5 grid: attribute %zu has no name", i);
    return BKF_OK;
}

/* Debian's HDF5 is not built thread-safe (its global state, the error
 * stack, the open-file list where the core driver's fixed name would
 * clash): every HDF5 call of the library is made under this lock, so that
 * a sweep's threads may each write their point's field.  The file's bytes
 * go to the disk outside it. */
static pthread_mutex_t h5_lock = PTHREAD_MUTEX_INITIALIZER;

/* The file's image in memory (malloc'ed), or a status. */
static int build_image(const bkf_h5_grid *g, void **image_out, ssize_t *size_out,
                       bkf_error *err);

/* Loads HDF5 once per process (under h5_lock; bkf_lazy_open): BKF_OK, or
 * BKF_EIO with what is missing, said again at every later call.  The
 * predefined types' ids are variables of the library, read once H5open has
 * set them. */
static int load_hdf5(bkf_error *err)
{
    static int loaded; /* 0: not tried, 1: loaded, else the failure's status */
    static bkf_error failure;
    if (loaded == 1) return BKF_OK;
    if (loaded) {
        if (err) *err = failure;
        return loaded;
    }
#define H5_NAME(f) #f,
    static const char *const names[] = {H5_FUNCTIONS(H5_NAME) H5_IDS(H5_NAME)};
    static const char *const hl_names[] = {H5_HL_FUNCTIONS(H5_NAME)};
    enum { NNAMES = sizeof names / sizeof *names, NHL = sizeof hl_names / sizeof *hl_names };
    void *p[NNAMES], *hl[NHL];
    bkf_error e;
    int s = bkf_lazy_open(BKF_HDF5_SONAME, "libhdf5-dev", names, p, NNAMES, &e);
    if (!s) s = bkf_lazy_open(BKF_HDF5_HL_SONAME, "libhdf5-dev", hl_names, hl, NHL, &e);
    if (s) {
        s = bkf_error_set(&failure, s, "HDF5 output needs the HDF5 library bkfront was built "
                          "with (%d.%d.%d): %s", H5_VERS_MAJOR, H5_VERS_MINOR, H5_VERS_RELEASE,
                          e.message);
    } else {
        size_t i = 0, k = 0;
#define H5_SET(f) h5.f = (__typeof__(f) *)p[i++];
#define H5_SET_HL(f) h5.f = (__typeof__(f) *)hl[k++];
        H5_FUNCTIONS(H5_SET)
        H5_HL_FUNCTIONS(H5_SET_HL)
        unsigned major = 0, minor = 0, release = 0;
        if (h5.H5open() < 0 || h5.H5get_libversion(&major, &minor, &release) < 0)
            s = bkf_error_set(&failure, BKF_EIO, "HDF5 output: the HDF5 library does not start");
        /* HDF5 changes its ABI between minor versions */
        if (!s && (major != H5_VERS_MAJOR || minor != H5_VERS_MINOR))
            s = bkf_error_set(&failure, BKF_EIO, "HDF5 output: %s is HDF5 %u.%u.%u, bkfront was "
                              "built with %d.%d.%d", BKF_HDF5_SONAME, major, minor, release,
                              H5_VERS_MAJOR, H5_VERS_MINOR, H5_VERS_RELEASE);
#define H5_SET_ID(v) h5.v = *(const hid_t *)p[i++];
        if (!s) { H5_IDS(H5_SET_ID) }
    }
    loaded = s ? s : 1;
    if (s && err) *err = failure;
    return s;
}

int bkf_h5_write(bkf_io_atomic *file, const bkf_h5_grid *g, bkf_error *err)
{
    int s = check_grid(g, err);
    if (s) return s;
    FILE *stream = bkf_io_atomic_stream(file);
    if (!stream) return bkf_error_set(err, BKF_EINPUT, "HDF5 output: no file to write into");
    void *image = NULL;
    ssize_t size = 0;
    pthread_mutex_lock(&h5_lock);
    s = load_hdf5(err);
    if (!s) s = build_image(g, &image, &size, err);
    pthread_mutex_unlock(&h5_lock);
    if (s) return s;
    int bad = fwrite(image, 1, (size_t)size, stream) != (size_t)size || fflush(stream) != 0;
    free(image);
    if (bad) return bkf_error_set(err, BKF_EIO, "writing the HDF5 file failed: %s",
                                  strerror(errno));
    return BKF_OK;
}

static int build_image(const bkf_h5_grid *g, void **image_out, ssize_t *size_out,
                       bkf_error *err)
{

    /* HDF5 prints its error stack by default: a library must not. */
    H5E_auto2_t old_func = NULL;
    void *old_data = NULL;
    if (h5.H5Eget_auto2(H5E_DEFAULT, &old_func, &old_data) < 0 ||
        h5.H5Eset_auto2(H5E_DEFAULT, NULL, NULL) < 0)
        return bkf_error_set(err, BKF_EIO, "HDF5 output: the HDF5 library does not start");
    writer w = {.file = -1, .scale = {-1, -1}};
    /* The file is built in memory (the core driver, no backing store) and
     * its image goes through the atomic writer's stream: HDF5 never writes
     * to a file itself.  A write that fails inside HDF5 leaves a file it can
     * neither close nor forget (1.10 then crashes at exit), and a file
     * reopened by name could be another one. */
    /* The core driver grows its image by whole increments (and zeroes
     * them): one increment a little above the raw data holds the whole
     * file (chunk indices and headers add ~2%), so the peak is the image
     * once, not twice. */
    double bytes = 1048576.0 + 8.0 * (double)(g->rows.count + g->columns.count) +
                   1.05 * 4.0 * (double)g->nfields * (double)g->rows.count *
                       (double)g->columns.count;
    if (g->deflate) bytes /= 8; /* grown as needed */
    size_t increment = bytes > 268435456.0 ? 268435456u : (size_t)bytes;
    hid_t fapl = h5.H5Pcreate(h5.H5P_CLS_FILE_ACCESS_ID_g);
    int ok = check(&w, fapl >= 0, "H5Pcreate");
    /* a strong close closes whatever is still open on a failure */
    if (ok) ok = check(&w, h5.H5Pset_fapl_core(fapl, increment, 0) >= 0, "H5Pset_fapl_core") &&
                 check(&w, h5.H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG) >= 0,
                       "H5Pset_fclose_degree");
    /* No modification times in the objects: the same field is the same
     * bytes (a sweep's point, computed again or elsewhere, gives its file
     * bit for bit). */
    hid_t fcpl = ok ? h5.H5Pcreate(h5.H5P_CLS_FILE_CREATE_ID_g) : -1;
    if (ok) ok = check(&w, fcpl >= 0, "H5Pcreate") &&
                 check(&w, h5.H5Pset_obj_track_times(fcpl, 0) >= 0, "H5Pset_obj_track_times");
    if (ok) ok = check(&w, (w.file = h5.H5Fcreate("bkfront-spacetime.h5", H5F_ACC_TRUNC,
                                               fcpl, fapl)) >= 0, "H5Fcreate");
    if (fcpl >= 0) ok = check(&w, h5.H5Pclose(fcpl) >= 0, "H5Pclose") && ok;
    if (fapl >= 0) ok = check(&w, h5.H5Pclose(fapl) >= 0, "H5Pclose") && ok;
    if (ok) ok = axis(&w, 0, &g->rows) && axis(&w, 1, &g->columns);
    for (size_t i = 0; ok && i < g->nfields; i++) ok = field(&w, g, &g->fields[i]);
    for (size_t i = 0; ok && i < g->nattributes; i++) ok = attribute(&w, w.file, &g->attributes[i]);
    for (int k = 0; k < 2; k++)
        if (w.scale[k] >= 0) ok = check(&w, h5.H5Dclose(w.scale[k]) >= 0, "H5Dclose") && ok;
    void *image = NULL;
    ssize_t size = -1;
    if (ok) ok = check(&w, h5.H5Fflush(w.file, H5F_SCOPE_GLOBAL) >= 0, "H5Fflush") &&
                 check(&w, (size = h5.H5Fget_file_image(w.file, NULL, 0)) > 0, "H5Fget_file_image");
    if (ok && !(image = malloc((size_t)size))) {
        h5.H5Eset_auto2(H5E_DEFAULT, old_func, old_data);
        h5.H5Fclose(w.file);
        return bkf_error_set(err, BKF_ENOMEM, "HDF5 output: out of memory for a %zd-byte file",
                             size);
    }
    if (ok) ok = check(&w, h5.H5Fget_file_image(w.file, image, (size_t)size) == size,
                       "H5Fget_file_image");
    if (w.file >= 0) ok = check(&w, h5.H5Fclose(w.file) >= 0, "H5Fclose") && ok;
    h5.H5Eset_auto2(H5E_DEFAULT, old_func, old_data);
    if (!ok) {
        free(image);
        return bkf_error_set(err, BKF_EIO, "writing the HDF5 file failed: %s: %s", w.step,
                             w.cause[0] ? w.cause : "no description");
    }
    *image_out = image;
    *size_out = size;
    return BKF_OK;
}
