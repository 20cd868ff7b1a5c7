/* The MPI farm of bkfront sweep (sweep_mpi.h). */
#define _POSIX_C_SOURCE 200809L
#include "sweep_mpi.h"

#ifndef BKF_MPI

int sweep_mpi_start(int *argc, char ***argv)
{
    (void)argc, (void)argv;
    return 0;
}

int sweep_mpi_on(void) { return 0; }

int sweep_mpi_check(const bkf_sweep_spec *spec, bkf_error *err)
{
    (void)spec, (void)err;
    return BKF_OK;
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
#include <omp.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { TAG_READY = 1, TAG_ROW, TAG_FAIL, TAG_WORK, TAG_STOP };

static int started, rank, size = 1, provided;

int sweep_mpi_start(int *argc, char ***argv)
{
    /* Only under a launcher: a plain `bkfront sweep` of the MPI build
     * stays one process without starting MPI's runtime. */
    if (!getenv("OMPI_COMM_WORLD_SIZE") && !getenv("PMI_SIZE") && !getenv("PMIX_RANK")) return 0;
    /* Serialized: the compute threads of a rank (--threads) take turns
     * at asking rank 0 for points; rank 0's own compute threads make no
     * MPI call at all. */
    if (MPI_Init_thread(argc, argv, MPI_THREAD_SERIALIZED, &provided) != MPI_SUCCESS) return 0;
    started = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    if (rank != 0 && !freopen("/dev/null", "w", stderr)) return rank;
    return rank;
}

int sweep_mpi_on(void) { return started; }

int sweep_mpi_check(const bkf_sweep_spec *sp, bkf_error *err)
{
    if (!started) return BKF_OK;
    if (sp->of > 1)
        return bkf_error_set(err, BKF_EINPUT, "--of: not with mpirun (the farm spreads the points)");
    int threads = sp->threads ? (int)sp->threads : 1;
    if (provided < MPI_THREAD_FUNNELED || (threads > 1 && provided < MPI_THREAD_SERIALIZED))
        return bkf_error_set(err, BKF_EINPUT,
                             "--threads: this MPI library runs no threads (MPI_THREAD_%s)%s",
                             threads > 1 ? "SERIALIZED" : "FUNNELED",
                             threads > 1 ? "; give 1" : "");
    return BKF_OK;
}

int sweep_mpi_size(void) { return size; }

int sweep_mpi_agree(int status)
{
    MPI_Bcast(&status, 1, MPI_INT, 0, MPI_COMM_WORLD);
    return status;
}

int sweep_mpi_end(int status)
{
    /* Stopped by a signal: mpirun (Open MPI 4) answers its SIGTERM or
     * SIGINT with SIGCONT to every rank, SIGTERM a second later, and
     * SIGKILL to every rank as soon as the first of them ends.  Rank 0
     * must be that one, its "interrupted" line written: a rank with no
     * point in flight ended within a millisecond, and under load rank 0,
     * still closing its table, was killed before its line.  The others
     * have nothing to write; they wait for that SIGKILL (at most 10 s,
     * under a launcher that sends none).  MPI_Finalize would wait for
     * the torn-down job; the table is closed already. */
    if (started && status == BKF_ECANCELED && rank != 0)
        for (int i = 0; i < 1000; i++) nanosleep(&(struct timespec){0, 10000000}, NULL);
    if (started && status != BKF_ECANCELED) MPI_Finalize();
    return status;
}

/* Rank 0's state, shared by its manager (the main thread: every MPI call
 * of rank 0) and its compute threads. */
typedef struct {
    const bkf_sweep_spec *sp;
    bkf_sweep_table *table;
    progress_bar *bar;
    size_t count, next, todo, finished;
    int status, unwritable;
    bkf_error *err;
    pthread_mutex_t lock;
} farm;

/* The next point nobody has (0: none left, or the sweep stops). */
static int claim(farm *f, size_t *index)
{
    pthread_mutex_lock(&f->lock);
    const unsigned char *done = bkf_sweep_table_done(f->table);
    while (f->next < f->count && done[f->next]) f->next++;
    if (!f->status && f->sp->cancel && *f->sp->cancel)
        f->status = bkf_error_set(f->err, BKF_ECANCELED, "canceled");
    int got = !f->status && f->next < f->count;
    if (got) *index = f->next++;
    pthread_mutex_unlock(&f->lock);
    return got;
}

/* A point's row to the table, or its failure (row NULL, e) to the farm:
 * the first failure stops the handing out.  A row that finishes after
 * that (a signal, another point's failure) is still a finished row: kept
 * unless the table itself failed. */
static void deliver(farm *f, size_t index, const char *row, const bkf_error *e)
{
    pthread_mutex_lock(&f->lock);
    bkf_error mine = {0};
    int s = BKF_OK;
    if (row && !f->unwritable) {
        s = bkf_sweep_table_append(f->table, index, row, &mine);
        f->unwritable = s != BKF_OK;
        if (!s) progress_count(f->bar, ++f->finished, f->todo);
    } else if (!row) {
        s = e->status ? e->status : BKF_EIO;
        mine = *e;
    }
    if (s && !f->status) f->status = bkf_error_set(f->err, s, "%s", mine.message);
    pthread_mutex_unlock(&f->lock);
}

/* A compute thread of rank 0. */
static void compute(farm *f)
{
    for (size_t i; claim(f, &i);) {
        bkf_error e = {0};
        char *row = bkf_sweep_row(f->sp, i, &e);
        deliver(f, i, row, &e);
        free(row);
    }
}

/* Rank 0's main thread: waits for a message without spinning a core that
 * a compute thread could use (a blocking receive polls in OpenMPI); 1 ms
 * is far below a point's run.  0 once the sweep is canceled: mpirun
 * SIGKILLs the job a second after its SIGTERM, and waiting for the other
 * ranks' last messages (a loaded machine can take longer than that) would
 * lose rank 0's own "interrupted" line; their points in flight are not in
 * the table and --resume computes them again. */
static int probe(const farm *f, MPI_Status *st)
{
    for (int flag = 0;;) {
        if (f->sp->cancel && *f->sp->cancel) return 0;
        MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, st);
        if (flag) return 1;
        nanosleep(&(struct timespec){0, 1000000}, NULL);
    }
}

/* Hands out points to the compute threads of ranks 1 .. K-1 as they ask,
 * until every one of them is told to stop.  Each rank's thread 0 says in
 * its first message how many threads the rank has (OpenMP may give fewer
 * than asked), so every thread is waited for exactly. */
static void manage(farm *f)
{
    long unannounced = size - 1, running = 0;
    char *buf = NULL;
    while (unannounced > 0 || running > 0) {
        MPI_Status st;
        size_t i;
        if (!probe(f, &st)) {
            claim(f, &i); /* claims nothing now: records the cancellation */
            break;
        }
        int len;
        MPI_Get_count(&st, MPI_CHAR, &len);
        char *g = realloc(buf, (size_t)len + 1);
        /* without room for a message the farm cannot go on; every finished
         * row is on disk already */
        if (!g) MPI_Abort(MPI_COMM_WORLD, 1);
        buf = g;
        MPI_Recv(buf, len, MPI_CHAR, st.MPI_SOURCE, st.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        buf[len] = '\0';
        if (st.MPI_TAG == TAG_READY && atoi(buf) > 0) {
            unannounced--;
            running += atoi(buf);
        } else if (st.MPI_TAG == TAG_ROW) {
            /* "INDEX\tREST": the row itself starts with its index */
            deliver(f, strtoull(buf, NULL, 10), buf, NULL);
        } else if (st.MPI_TAG == TAG_FAIL) {
            bkf_error e = {.status = buf[0] ? atoi(buf) : BKF_EIO};
            const char *text = strchr(buf, ' ') ? strchr(buf, ' ') + 1 : buf;
            snprintf(e.message, sizeof e.message, "%s", text);
            deliver(f, 0, NULL, &e);
        }
        if (claim(f, &i)) {
            uint64_t w = i;
            MPI_Send(&w, 1, MPI_UINT64_T, st.MPI_SOURCE, TAG_WORK, MPI_COMM_WORLD);
        } else {
            MPI_Send(NULL, 0, MPI_UINT64_T, st.MPI_SOURCE, TAG_STOP, MPI_COMM_WORLD);
            running--;
        }
    }
    free(buf);
}

/* Rank 0's answer to a message of this thread, waited for as probe waits
 * (a blocking receive polls in OpenMPI: a core spinning beside the
 * compute threads); 0, the request withdrawn, once the sweep is canceled:
 * rank 0 no longer answers then (see probe), and the rank goes on to wait
 * in sweep_mpi_end without spinning. */
static int answer(const bkf_sweep_spec *sp, uint64_t *i, MPI_Status *st)
{
    MPI_Request rq;
    MPI_Irecv(i, 1, MPI_UINT64_T, 0, MPI_ANY_TAG, MPI_COMM_WORLD, &rq);
    for (int flag = 0;;) {
        MPI_Test(&rq, &flag, st);
        if (flag) return 1;
        if (sp->cancel && *sp->cancel) {
            MPI_Cancel(&rq);
            MPI_Wait(&rq, MPI_STATUS_IGNORE);
            return 0;
        }
        nanosleep(&(struct timespec){0, 1000000}, NULL);
    }
}

/* A compute thread of ranks 1 .. K-1: its message (the first: the rank's
 * thread count) and the answer, a point or stop, are one exchange that
 * the rank's other threads do not interleave with theirs. */
static void serve(const bkf_sweep_spec *sp)
{
    char *msg = NULL;
    int tag = TAG_READY;
    char ready[32];
    snprintf(ready, sizeof ready, "%d", omp_get_thread_num() == 0 ? omp_get_num_threads() : 0);
    for (;;) {
        uint64_t i;
        MPI_Status st;
        const char *out = msg ? msg : ready;
        /* stopped by a signal: rank 0 no longer listens (see probe) */
        if (sp->cancel && *sp->cancel) break;
        int answered = 0;
#pragma omp critical(bkf_sweep_mpi)
        if (!(sp->cancel && *sp->cancel)) {
            MPI_Send(out, (int)strlen(out), MPI_CHAR, 0, tag, MPI_COMM_WORLD);
            answered = answer(sp, &i, &st);
        }
        free(msg);
        msg = NULL;
        if (!answered || st.MPI_TAG == TAG_STOP) break;
        bkf_error e = {0};
        if ((msg = bkf_sweep_row(sp, (size_t)i, &e))) {
            tag = TAG_ROW;
        } else {
            tag = TAG_FAIL;
            size_t n = BKF_ERROR_LEN + 16;
            if ((msg = malloc(n))) snprintf(msg, n, "%d %s", e.status, e.message);
        }
        /* out of memory for the message itself: the failure without text */
        if (!msg) snprintf(ready, sizeof ready, "%d out of memory", BKF_ENOMEM);
    }
    free(msg);
}

int sweep_mpi_farm(const bkf_sweep_spec *sp, bkf_sweep_table *table, progress_bar *bar,
                   bkf_error *err)
{
    int threads = sp->threads ? (int)sp->threads : 1, s = BKF_OK;
    if (rank == 0) {
        farm f = {.sp = sp, .table = table, .bar = bar, .count = bkf_sweep_count(sp), .err = err};
        pthread_mutex_init(&f.lock, NULL);
        const unsigned char *done = bkf_sweep_table_done(table);
        for (size_t i = 0; i < f.count; i++) f.todo += !done[i];
        /* the main thread manages (MPI_THREAD_FUNNELED), the others compute;
         * alone (OpenMP gave no more threads), it computes after managing */
#pragma omp parallel num_threads(threads + 1)
        {
            if (omp_get_thread_num() == 0) {
                manage(&f);
                if (omp_get_num_threads() == 1) compute(&f);
            } else {
                compute(&f);
            }
        }
        pthread_mutex_destroy(&f.lock);
        s = f.status;
    } else {
#pragma omp parallel num_threads(threads)
        serve(sp);
    }
    /* every rank leaves with rank 0's verdict */
    return sweep_mpi_agree(s);
}

#endif
