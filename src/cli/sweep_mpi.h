/* bkfront sweep on an MPI farm: rank 0's main thread hands out points one
 * at a time as compute threads ask (dynamic assignment) and appends their
 * rows to the table as they arrive; every rank, rank 0 too, runs --threads
 * compute threads (default 1), one run each.  Built only by `make mpi`
 * (BKF_MPI); elsewhere these are the one-process answers. */
#ifndef BKFRONT_CLI_SWEEP_MPI_H
#define BKFRONT_CLI_SWEEP_MPI_H

#include "progress.h"

#include "bkfront/sweep.h"

/* Joins the MPI job when started by mpirun (or srun): this process's rank,
 * 0 otherwise.  Ranks other than 0 say nothing on stderr: one line per
 * failure, from rank 0. */
int sweep_mpi_start(int *argc, char ***argv);
/* Whether this process is in an MPI job (0 without a launcher). */
int sweep_mpi_on(void);
/* What the farm cannot do (--of; threads the MPI library does not
 * support), the same verdict on every rank. */
int sweep_mpi_check(const bkf_sweep_spec *spec, bkf_error *err);
/* Processes in the job (1 without MPI). */
int sweep_mpi_size(void);
/* Rank 0's status, on every rank. */
int sweep_mpi_agree(int status);
/* The farm (size > 1): on rank 0 rows go to `table` (the points it marks
 * done are skipped) and `bar`; a failure stops the handing out, and rows
 * that finish after it are still kept. */
int sweep_mpi_farm(const bkf_sweep_spec *spec, bkf_sweep_table *table, progress_bar *bar,
                   bkf_error *err);
/* Leaves the job; returns status. */
int sweep_mpi_end(int status);

#endif
