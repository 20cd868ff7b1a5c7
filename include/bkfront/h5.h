/* Fields on a two-dimensional grid as an HDF5 file that h5py and xarray
 * read directly: each axis a one-dimensional dataset made an HDF5
 * dimension scale (H5DS) of its own name, each field a float32 dataset of
 * shape (rows, columns) with the axes attached, chunked and optionally
 * deflate-compressed, and the attributes on the root group.
 *
 * The file is built in memory by HDF5 (up to its size again besides the
 * fields) and its bytes written through the stream of an atomic writer
 * (io.h), so it takes the place of its target only at
 * bkf_io_atomic_commit, like every other output.  The HDF5 library's own error printing is switched off
 * while it works (and restored after); every HDF5 call is checked, and the
 * first failure is returned with HDF5's description of it.  HDF5 itself is
 * not linked: the first write loads it (the soname bkfront was compiled
 * against), and where it cannot be loaded every write is BKF_EIO with a
 * message naming it; nothing else needs HDF5.  Thread-safe:
 * the HDF5 calls of concurrent writes are made one write at a time (the
 * HDF5 library itself is not built thread-safe). */
#ifndef BKFRONT_H5_H
#define BKFRONT_H5_H

#include <stddef.h>
#include "bkfront/io.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    const char *name;      /* dataset and dimension name, e.g. "t" */
    const double *values;  /* count values */
    size_t count;
    const char *long_name; /* attribute long_name, or NULL */
} bkf_h5_axis;

typedef struct {
    const char *name;      /* dataset name, e.g. "psi" */
    const float *values;   /* rows x columns, row after row */
    const char *long_name; /* attribute long_name, or NULL */
} bkf_h5_field;

typedef enum { BKF_H5_DOUBLE = 0, BKF_H5_INT = 1, BKF_H5_TEXT = 2 } bkf_h5_kind;

typedef struct {
    const char *name;
    bkf_h5_kind kind;
    double number;         /* BKF_H5_DOUBLE */
    long long integer;     /* BKF_H5_INT */
    const char *text;      /* BKF_H5_TEXT: UTF-8, variable length (str in h5py) */
} bkf_h5_attribute;

typedef struct {
    bkf_h5_axis rows, columns;     /* the fields' first and second dimension */
    const bkf_h5_field *fields;
    size_t nfields;
    const bkf_h5_attribute *attributes; /* of the root group */
    size_t nattributes;
    unsigned deflate;              /* 0: none; 1..9: gzip level (with shuffle) */
} bkf_h5_grid;

#define BKF_H5_DEFLATE_MAX 9

/* Writes `grid` into the stream of `file` (not yet committed).
 * BKF_EINPUT for a grid without fields, names or values, a repeated name or
 * deflate above 9; BKF_ENOMEM; BKF_EIO when HDF5 or the write fails (the caller then aborts the
 * file, so that no part of it is ever seen under the target's name). */
int bkf_h5_write(bkf_io_atomic *file, const bkf_h5_grid *grid, bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif
