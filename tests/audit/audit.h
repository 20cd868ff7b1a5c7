/* The project's audit (make audit; docs/testing.md, "The audit"): random
 * parameter sets from the documented domain, extremes included, each
 * product checked against an independent route that the project has
 * (another integrator, Hill's method against the monodromy, the Taylor
 * reference of tests/wave, a direct scan of the speed condition, the
 * check's verdict against the spectrum, the line at kappa 0 against the
 * ring at j 0).  Every row is OK, a DEFECT (with the command that
 * reproduces it) or a REFUSAL (with its reason). */
#ifndef BKF_AUDIT_H
#define BKF_AUDIT_H

#include <stddef.h>
#include <stdio.h>

typedef struct {
    double gamma, c, nu, S;
    const char *kind; /* how it was drawn: uniform, nu-edge, gamma-small, gamma-large, c-near-v, given */
} audit_set;

typedef enum { AUDIT_OK = 0, AUDIT_DEFECT = 1, AUDIT_REFUSAL = 2 } audit_status;

/* What one set audits; all on by default. */
typedef struct {
    int period, speeds, scan, stability, line, check, floquet;
    size_t n_max;   /* speed rows for n = 1..n_max; default 4 */
} audit_options;

audit_options audit_options_default(void);

/* Set i of the sample with this seed: a deterministic function of (seed,
 * i), so that any set is drawn again alone.  Every sixth is uniform over
 * gamma 0.3-8, c 0.05-1.5, nu -0.99..0.99, S 5-60; the others push one
 * parameter to an extreme (|nu| > 0.95, gamma < 0.6, gamma > 6, or S
 * just above a multiple of k(nu) c gamma, where the slowest root's v is
 * near c). */
audit_set audit_draw(unsigned long seed, size_t i);

/* One result row, as a line "set<TAB>product<TAB>status<TAB>detail<TAB>reproducer". */
typedef struct {
    size_t set;
    char product[16];
    audit_status status;
    char detail[400];
    char repro[300];
} audit_row;

typedef struct {
    audit_row *rows;
    size_t count, capacity;
} audit_rows;

/* Audits one set, appending its rows.  Never fails: what cannot be
 * computed is a refusal row with its reason. */
void audit_run_set(size_t index, const audit_set *set, const audit_options *options, audit_rows *out);

void audit_rows_free(audit_rows *rows);
void audit_row_write(FILE *f, const audit_row *r);
/* Parses a line of audit_row_write; 0 on success. */
int audit_row_read(const char *line, audit_row *r);

const char *audit_status_name(audit_status s);

/* The table: per product OK / defect / refusal, then every defect with its
 * reproducer, then refusals' reasons (at most `refusals_shown`).  Returns
 * the number of defects. */
size_t audit_report(FILE *f, const audit_rows *rows, size_t refusals_shown);

#endif
