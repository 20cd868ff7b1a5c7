/* The MPI farm of bkfront sweep (sweep_mpi.h). */
#define _POSIX_C_SOURCE 200809L
#include "sweep_mpi.h"

#ifndef BKF_MPI

int sweep_mpi_start(int *argc, char ***argv)
{
    (void)argc, (void)argv;
    return 0;
}

int sweep_mpi_size(void) { return 1; }

int sweep_mpi_agree(int status) { return status; }

int sweep_mpi_farm(const bkf_sweep_spec *spec, bkf_sweep_table *table, progress_bar *bar,
                   bkf_error *err)
{
    (void)spec, (void)table, (void)bar;
    return bkf_error_set(err, BKF_EINPUT, "this bkfront is built without MPI (make mpi)");
}

int sweep_mpi_end(int status) { return status; }

#else

#include <mpi.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { TAG_READY = 1, TAG_ROW, TAG_FAIL, TAG_WORK, TAG_STOP };

static int started, rank, size = 1;

int sweep_mpi_start(int *argc, char ***argv)
{
    /* Only under a launcher: a plain `bkfront sweep` of the MPI build
     * stays one process without starting MPI's runtime. */
    if (!getenv("OMPI_COMM_WORLD_SIZE") && !getenv("PMI_SIZE") && !getenv("PMIX_RANK")) return 0;
    if (MPI_Init(argc, argv) != MPI_SUCCESS) return 0;
    started = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    if (rank != 0 && !freopen("/dev/null", "w", stderr)) return rank;
    return rank;
}

int sweep_mpi_size(void) { return size; }

int sweep_mpi_agree(int status)
{
    MPI_Bcast(&status, 1, MPI_INT, 0, MPI_COMM_WORLD);
    return status;
}

int sweep_mpi_end(int status)
{
    if (started) MPI_Finalize();
    return status;
}

/* Rank 0: waits for a message without spinning a core that a worker
 * could use (a blocking receive polls in OpenMPI); 1 ms is far below a
 * point's run. */
static void probe(MPI_Status *st)
{
    for (int flag = 0;;) {
        MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, st);
        if (flag) return;
        nanosleep(&(struct timespec){0, 1000000}, NULL);
    }
}

static int manager(const bkf_sweep_spec *sp, bkf_sweep_table *table, progress_bar *bar,
                   bkf_error *err)
{
    size_t count = bkf_sweep_count(sp), next = 0, todo = 0, finished = 0;
    const unsigned char *done = bkf_sweep_table_done(table);
    for (size_t i = 0; i < count; i++) todo += !done[i];
    int s = BKF_OK, active = size - 1;
    char *buf = NULL;
    while (active > 0) {
        MPI_Status st;
        probe(&st);
        int len;
        MPI_Get_count(&st, MPI_CHAR, &len);
        char *g = realloc(buf, (size_t)len + 1);
        if (!g) {
            s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
            break;
        }
        buf = g;
        MPI_Recv(buf, len, MPI_CHAR, st.MPI_SOURCE, st.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        buf[len] = '\0';
        if (st.MPI_TAG == TAG_ROW && !s) {
            /* "INDEX\tREST": the row itself starts with its index */
            size_t index = strtoull(buf, NULL, 10);
            s = bkf_sweep_table_append(table, index, buf, err);
            if (!s) progress_count(bar, ++finished, todo);
        } else if (st.MPI_TAG == TAG_FAIL && !s) {
            s = bkf_error_set(err, buf[0] ? atoi(buf) : BKF_EIO, "%s",
                              strchr(buf, ' ') ? strchr(buf, ' ') + 1 : buf);
        }
        while (next < count && done[next]) next++;
        if (!s && sp->cancel && *sp->cancel) s = bkf_error_set(err, BKF_ECANCELED, "canceled");
        if (!s && next < count) {
            uint64_t i = next++;
            MPI_Send(&i, 1, MPI_UINT64_T, st.MPI_SOURCE, TAG_WORK, MPI_COMM_WORLD);
        } else {
            MPI_Send(NULL, 0, MPI_UINT64_T, st.MPI_SOURCE, TAG_STOP, MPI_COMM_WORLD);
            active--;
        }
    }
    free(buf);
    return s;
}

static int worker(const bkf_sweep_spec *sp)
{
    MPI_Send(NULL, 0, MPI_CHAR, 0, TAG_READY, MPI_COMM_WORLD);
    for (;;) {
        uint64_t i;
        MPI_Status st;
        MPI_Recv(&i, 1, MPI_UINT64_T, 0, MPI_ANY_TAG, MPI_COMM_WORLD, &st);
        if (st.MPI_TAG == TAG_STOP) return BKF_OK;
        bkf_error e = {0};
        char *row = bkf_sweep_row(sp, (size_t)i, &e);
        if (row) {
            MPI_Send(row, (int)strlen(row), MPI_CHAR, 0, TAG_ROW, MPI_COMM_WORLD);
            free(row);
        } else {
            char msg[BKF_ERROR_LEN + 16];
            snprintf(msg, sizeof msg, "%d %s", e.status, e.message);
            MPI_Send(msg, (int)strlen(msg), MPI_CHAR, 0, TAG_FAIL, MPI_COMM_WORLD);
        }
    }
}

int sweep_mpi_farm(const bkf_sweep_spec *sp, bkf_sweep_table *table, progress_bar *bar,
                   bkf_error *err)
{
    int s = rank == 0 ? manager(sp, table, bar, err) : worker(sp);
    /* every rank leaves with the manager's verdict */
    return sweep_mpi_agree(s);
}

#endif
