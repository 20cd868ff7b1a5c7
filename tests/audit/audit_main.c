/* make audit: the audit program (tests/audit/audit.h; docs/testing.md).
 *
 *   build/audit [--sets N] [--seed S] [--jobs J] [--from I] [--set G,C,NU,S]...
 *               [--no-check] [--no-scan] [--rows FILE]
 *
 * Sets are audited in J forked workers (each set is independent); every
 * worker writes its rows to a file of its own, the parent merges them,
 * prints the table and exits 1 when a defect was found. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "audit.h"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static int usage(const char *msg)
{
    fprintf(stderr, "audit: %s\nusage: audit [--sets N] [--seed S] [--jobs J] [--from I] [--set G,C,NU,S]... "
                    "[--no-check] [--no-scan] [--rows FILE]\n", msg);
    return 2;
}

int main(int argc, char **argv)
{
    size_t nsets = 200, from = 0, jobs = 2;
    unsigned long seed = 1;
    const char *rows_path = NULL;
    audit_options opt = audit_options_default();
    audit_set given[64];
    size_t ngiven = 0;
    const char *env;
    if ((env = getenv("AUDIT_SETS")) && *env) nsets = strtoul(env, NULL, 10);
    if ((env = getenv("AUDIT_SEED")) && *env) seed = strtoul(env, NULL, 10);
    if ((env = getenv("AUDIT_JOBS")) && *env) jobs = strtoul(env, NULL, 10);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--sets") && v) nsets = strtoul(argv[++i], NULL, 10);
        else if (!strcmp(a, "--seed") && v) seed = strtoul(argv[++i], NULL, 10);
        else if (!strcmp(a, "--jobs") && v) jobs = strtoul(argv[++i], NULL, 10);
        else if (!strcmp(a, "--from") && v) from = strtoul(argv[++i], NULL, 10);
        else if (!strcmp(a, "--rows") && v) rows_path = argv[++i];
        else if (!strcmp(a, "--no-check")) opt.check = 0;
        else if (!strcmp(a, "--no-scan")) opt.scan = 0;
        else if (!strcmp(a, "--set") && v && ngiven < 64) {
            audit_set s = {0, 0, 0, 0, "given"};
            if (sscanf(argv[++i], "%lf,%lf,%lf,%lf", &s.gamma, &s.c, &s.nu, &s.S) != 4)
                return usage("--set: four numbers G,C,NU,S");
            given[ngiven++] = s;
        } else {
            return usage("unknown or incomplete option");
        }
    }
    if (jobs < 1 || jobs > 64) return usage("--jobs: in [1, 64]");
    size_t total = ngiven ? ngiven : nsets;
    audit_set *sets = calloc(total ? total : 1, sizeof *sets);
    if (!sets) return 1;
    for (size_t i = 0; i < total; i++) sets[i] = ngiven ? given[i] : audit_draw(seed, from + i);

    double t0 = now();
    FILE *parts[64];
    pid_t pids[64];
    for (size_t w = 0; w < jobs; w++) {
        parts[w] = tmpfile();
        if (!parts[w]) return perror("audit: tmpfile"), 1;
        fflush(NULL);
        pids[w] = fork();
        if (pids[w] < 0) return perror("audit: fork"), 1;
        if (pids[w] == 0) {
            for (size_t i = w; i < total; i += jobs) {
                double ts = now();
                clock_t cs = clock();
                audit_rows rows = {0};
                audit_run_set(ngiven ? i : from + i, &sets[i], &opt, &rows);
                for (size_t k = 0; k < rows.count; k++) audit_row_write(parts[w], &rows.rows[k]);
                fprintf(parts[w], "#time\t%zu\t%.3f\t%.3f\n", ngiven ? i : from + i, now() - ts,
                        (double)(clock() - cs) / CLOCKS_PER_SEC);
                fflush(parts[w]);
                audit_rows_free(&rows);
            }
            _exit(ferror(parts[w]) ? 1 : 0);
        }
    }
    int failed = 0;
    for (size_t w = 0; w < jobs; w++) {
        int status;
        while (waitpid(pids[w], &status, 0) < 0 && errno == EINTR) {}
        if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) failed = 1;
    }
    double wall = now() - t0;

    audit_rows all = {0};
    double set_time = 0.0, set_cpu = 0.0, slowest = 0.0;
    size_t slowest_set = 0;
    FILE *rows_out = rows_path ? fopen(rows_path, "w") : NULL;
    if (rows_path && !rows_out) return perror(rows_path), 1;
    char line[2048];
    for (size_t w = 0; w < jobs; w++) {
        rewind(parts[w]);
        while (fgets(line, sizeof line, parts[w])) {
            if (!strncmp(line, "#time\t", 6)) {
                size_t s;
                double t, cpu = 0.0;
                if (sscanf(line + 6, "%zu\t%lf\t%lf", &s, &t, &cpu) >= 2) {
                    set_time += t;
                    set_cpu += cpu;
                    if (t > slowest) slowest = t, slowest_set = s;
                }
                continue;
            }
            if (all.count == all.capacity) {
                size_t cap = all.capacity ? 2 * all.capacity : 256;
                audit_row *g = realloc(all.rows, cap * sizeof *g);
                if (!g) return 1;
                all.rows = g;
                all.capacity = cap;
            }
            if (audit_row_read(line, &all.rows[all.count]) == 0) all.count++;
        }
        fclose(parts[w]);
    }
    if (rows_out) {
        for (size_t i = 0; i < all.count; i++) audit_row_write(rows_out, &all.rows[i]);
        if (fclose(rows_out) != 0) return perror(rows_path), 1;
    }
    printf("audit: %zu sets (%s, seed %lu, from %zu), %zu jobs\n", total, ngiven ? "given" : "drawn", seed, from, jobs);
    for (size_t i = 0; i < total && total <= 20; i++)
        printf("  set %zu (%s): --gamma %.6g --c %.6g --nu %.6g --S %.6g\n", ngiven ? i : from + i, sets[i].kind,
               sets[i].gamma, sets[i].c, sets[i].nu, sets[i].S);
    size_t defects = audit_report(stdout, &all, 20);
    size_t refusals = 0;
    for (size_t i = 0; i < all.count; i++) refusals += all.rows[i].status == AUDIT_REFUSAL;
    printf("\naudit: %zu sets, %zu rows, %zu defects, %zu refusals; %.1f s (a set: %.1f s, %.1f s of processor; "
           "slowest set %zu %.1f s)%s\n",
           total, all.count, defects, refusals, wall, total ? set_time / total : 0.0, total ? set_cpu / total : 0.0,
           slowest_set, slowest, failed ? "; a worker failed" : "");
    audit_rows_free(&all);
    free(sets);
    return defects || failed ? 1 : 0;
}
