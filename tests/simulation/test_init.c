/* The simulation's set-up in the library: --init specifications, the state
 * file reader, the front seed through the speeds solver, the default front
 * level, the sampling of a run and the status codes of a failed run. */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bkfront/cycle.h"
#include "bkfront/init.h"
#include "bkfront/io.h"
#include "bkfront/measure.h"
#include "bkfront/model.h"
#include "bkfront/pde.h"
#include "bkfront/seed.h"
#include "bkfront/speeds.h"

/* Parses `text`, expecting failure with a message holding every one of
 * the NULL-terminated fragments. */
static void bad_spec(const char *text, ...)
{
    bkf_init_spec sp;
    bkf_error e = {0};
    int s = bkf_init_parse(text, &sp, &e);
    bkf_init_free(&sp);
    CHECK_MSG(s == BKF_EINPUT, "'%s' gave status %d", text, s);
    va_list ap;
    va_start(ap, text);
    for (const char *f; (f = va_arg(ap, const char *)) != NULL;)
        CHECK_MSG(strstr(e.message, f), "'%s': message '%s' lacks '%s'", text, e.message, f);
    va_end(ap);
}

TEST(init_parse_good_specs)
{
    bkf_init_spec sp;
    bkf_error e;
    CHECK_STATUS(bkf_init_parse("uniform", &sp, &e), BKF_OK);
    CHECK(sp.kind == BKF_INIT_UNIFORM && sp.amp == 1e-3 && sp.seed == 1);
    bkf_init_free(&sp);
    CHECK_STATUS(bkf_init_parse("uniform:amp=0.25", &sp, &e), BKF_OK);
    CHECK(sp.kind == BKF_INIT_UNIFORM && sp.amp == 0.25);
    bkf_init_free(&sp);
    CHECK_STATUS(bkf_init_parse("oscillation:j=3,amp=0.3", &sp, &e), BKF_OK);
    CHECK(sp.kind == BKF_INIT_OSCILLATION && sp.j == 3 && sp.amp == 0.3 && !sp.q_given);
    bkf_init_free(&sp);
    CHECK_STATUS(bkf_init_parse("oscillation", &sp, &e), BKF_OK);
    CHECK(sp.kind == BKF_INIT_OSCILLATION && sp.j == 0 && sp.amp == 0);
    bkf_init_free(&sp);
    CHECK_STATUS(bkf_init_parse("oscillation:q=2.83", &sp, &e), BKF_OK);
    CHECK(sp.q_given && sp.q == 2.83);
    /* q to the nearest mode 2 pi j/S: 2.83 * 20/(2 pi) = 9.008 */
    bkf_model_params model = {2, 0.3, -0.94, 20, 256, BKF_MODEL_CONTINUUM};
    bkf_pde_options o = bkf_pde_options_default();
    CHECK_STATUS(bkf_init_check(&sp, &model, 1, &o, &e), BKF_OK);
    CHECK(sp.j == 9);
    bkf_init_free(&sp);
    CHECK_STATUS(bkf_init_parse("front:n=6,root=2,dir=right,noise=0.01", &sp, &e), BKF_OK);
    CHECK(sp.kind == BKF_INIT_FRONT && sp.front.n == 6 && sp.front.root == 2 &&
          sp.front.direction == 1 && sp.front.noise == 0.01);
    bkf_init_free(&sp);
    CHECK_STATUS(bkf_init_parse("front:n=1", &sp, &e), BKF_OK);
    CHECK(sp.front.root == 1 && sp.front.direction == -1 && sp.front.noise == 0);
    bkf_init_free(&sp);
    CHECK_STATUS(bkf_init_parse("file:some/where.tsv", &sp, &e), BKF_OK);
    CHECK(sp.kind == BKF_INIT_FILE && strcmp(sp.path, "some/where.tsv") == 0 && !sp.state.psi);
    bkf_init_free(&sp);
    CHECK(sp.path == NULL);
}

TEST(init_parse_bad_specs_name_the_key_and_range)
{
    bad_spec("uniform:amp=11", "--init uniform amp", "outside [0, 10]", NULL);
    bad_spec("uniform:amp=-0.1", "amp", "[0, 10]", NULL);
    bad_spec("uniform:amp=nan", "amp", "not a finite number", NULL);
    bad_spec("uniform:amp=0x1p3", "amp", "not a number", NULL);
    bad_spec("uniform:amp=1e999", "amp", "too large", NULL);
    bad_spec("uniform:seed=3", "unknown key 'seed'", "(amp)", NULL);
    bad_spec("oscillation:q=-1", "--init oscillation q", ">= 0", NULL);
    bad_spec("oscillation:j=x", "--init oscillation j", "[1, 1048576]", NULL);
    bad_spec("oscillation:k=1", "unknown key 'k'", "(q, j, amp, noise)", NULL);
    bad_spec("front", "n=K is required", NULL);
    bad_spec("front:root=2", "n=K is required", NULL);
    bad_spec("front:n=0", "--init front n", "[1, 100000]", NULL);
    bad_spec("front:n=100001", "front n", "[1, 100000]", NULL);
    bad_spec("front:n=2,root=101", "--init front root", "[1, 100]", NULL);
    bad_spec("front:n=2,noise=20", "--init front noise", "[0, 10]", NULL);
    bad_spec("front:n=2,dir=up", "--init front dir", "'up' is not left or right", NULL);
    bad_spec("front:n=2,n", "'n' is not key=value", NULL);
    bad_spec("front:n=2,speed=3", "unknown key 'speed'", "(n, root, dir, noise)", NULL);
    bad_spec("file:", "give a path", NULL);
    bad_spec("bogus", "'bogus' is not one of", "uniform", "file:PATH", NULL);
    bad_spec("uni\nform", "'uni?form'", NULL); /* control characters shown as '?' */
    char longtext[400] = "uniform:";
    for (int i = 0; i < 60; i++) strcat(longtext, "amp=1,");
    bad_spec(longtext, "too long", NULL);
}

/* A stream holding `text`, or a stream that fails on reading. */
static FILE *text_stream(const char *text)
{
    FILE *f = tmpfile();
    CHECK(f != NULL);
    fputs(text, f);
    rewind(f);
    return f;
}

static int read_text(const char *text, size_t max_rows, bkf_io_state *st, bkf_error *e)
{
    FILE *f = text_stream(text);
    int s = bkf_io_read_state(f, max_rows, st, e);
    fclose(f);
    return s;
}

TEST(init_state_reader)
{
    bkf_io_state st;
    bkf_error e;
    /* two snapshots: only the last t is kept, in file order */
    const char *two = "# comment\n\nt\tx\tpsi\teta\n0\t0\t1\t2\n0\t1\t3\t4\n"
                      "5\t0\t-1.5\t0.25\n5\t1\t2e-3\t-7\n";
    CHECK_STATUS(read_text(two, 100, &st, &e), BKF_OK);
    CHECK(st.rows == 2 && st.has_t && st.t == 5);
    CHECK(st.psi[0] == -1.5 && st.eta[0] == 0.25 && st.psi[1] == 2e-3 && st.eta[1] == -7);
    bkf_io_state_free(&st);
    CHECK(st.psi == NULL && st.rows == 0);
    /* no t column: every row, any column order, CRLF line ends */
    CHECK_STATUS(read_text("eta\tpsi\r\n1\t2\r\n3\t4\r\n", 100, &st, &e), BKF_OK);
    CHECK(st.rows == 2 && !st.has_t && st.psi[1] == 4 && st.eta[1] == 3);
    bkf_io_state_free(&st);
    /* bad content: BKF_EINPUT naming the line, *state left empty */
    struct { const char *text, *fragment; } bad[] = {
        {"psi\tx\n1\t2\n", "header (line 1) must name the columns psi and eta"},
        {"# only comments\n", "no header line"},
        {"psi\teta\n1\t2\n1\tabc\n", "line 3: 'abc' is not a finite number"},
        {"psi\teta\n1\tnan\n", "line 2: 'nan' is not a finite number"},
        {"psi\teta\n1\t1e999\n", "not a finite number"},
        {"psi\teta\tx\n1\t2\n", "line 2 has 2 fields, not 3"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        CHECK_STATUS(read_text(bad[i].text, 100, &st, &e), BKF_EINPUT);
        CHECK_MSG(strstr(e.message, bad[i].fragment), "'%s' for case %zu", e.message, i);
        CHECK(st.psi == NULL && st.eta == NULL && st.rows == 0);
    }
    /* oversized: the limit counts every data row, refused at the first beyond */
    char big[4096] = "psi\teta\n";
    for (int i = 0; i < 50; i++) strcat(big, "0.5\t-0.5\n");
    CHECK_STATUS(read_text(big, 50, &st, &e), BKF_OK);
    CHECK(st.rows == 50);
    bkf_io_state_free(&st);
    CHECK_STATUS(read_text(big, 49, &st, &e), BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "line 51: more than 49 rows"), "%s", e.message);
    CHECK(st.psi == NULL);
    /* a stream that cannot be read: BKF_EIO */
    FILE *w = fopen("/dev/null", "w");
    CHECK(w != NULL);
    CHECK_STATUS(bkf_io_read_state(w, 100, &st, &e), BKF_EIO);
    fclose(w);
    CHECK_STATUS(bkf_io_read_state(NULL, 100, &st, &e), BKF_EINPUT);
}

TEST(init_load_and_check_a_state_file)
{
    char path[] = "/tmp/bkf_test_init_XXXXXX";
    int fd = mkstemp(path);
    CHECK(fd >= 0);
    FILE *f = fdopen(fd, "w");
    fputs("t\tx\tpsi\teta\n", f);
    for (int i = 0; i < 16; i++) fprintf(f, "3\t%d\t%g\t%g\n", i, -0.9 + 0.01 * i, 0.5);
    fclose(f);
    char spec[64];
    snprintf(spec, sizeof spec, "file:%s", path);
    bkf_init_spec sp;
    bkf_error e;
    CHECK_STATUS(bkf_init_parse(spec, &sp, &e), BKF_OK);
    CHECK_STATUS(bkf_init_load(&sp, &e), BKF_OK);
    CHECK(sp.state.rows == 16 && sp.state.t == 3);
    bkf_model_params model = {2, 0.3, -0.96, 20, 64, BKF_MODEL_CONTINUUM};
    bkf_pde_options o = bkf_pde_options_default();
    CHECK_STATUS(bkf_init_check(&sp, &model, 1, &o, &e), BKF_EINPUT); /* --N 64 given */
    CHECK_MSG(strstr(e.message, "--N: 64 differs from the 16 rows"), "%s", e.message);
    CHECK_STATUS(bkf_init_check(&sp, &model, 0, &o, &e), BKF_OK);
    CHECK(model.N == 16);
    bkf_pde *pde = bkf_pde_alloc(&model, &o, &e);
    CHECK(pde != NULL);
    CHECK_STATUS(bkf_seed_init(pde, &sp, NULL, NULL, &e), BKF_OK);
    CHECK(bkf_pde_psi(pde)[15] == -0.9 + 0.01 * 15 && bkf_pde_eta(pde)[3] == 0.5);
    CHECK(bkf_pde_time(pde) == 0);
    bkf_pde_free(pde);
    bkf_init_free(&sp);
    remove(path);
    /* a missing file is BKF_EIO, too few rows BKF_EINPUT */
    CHECK_STATUS(bkf_init_parse(spec, &sp, &e), BKF_OK);
    CHECK_STATUS(bkf_init_load(&sp, &e), BKF_EIO);
    CHECK_MSG(strstr(e.message, "--init file:") && strstr(e.message, path), "%s", e.message);
    bkf_init_free(&sp);
    f = fopen(path, "w");
    fputs("psi\teta\n1\t2\n", f);
    fclose(f);
    CHECK_STATUS(bkf_init_parse(spec, &sp, &e), BKF_OK);
    CHECK_STATUS(bkf_init_load(&sp, &e), BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "1 rows, need at least 8"), "%s", e.message);
    bkf_init_free(&sp);
    remove(path);
}

TEST(init_check_needs_a_cycle_and_a_mode_below_nyquist)
{
    bkf_init_spec sp;
    bkf_error e;
    bkf_pde_options o = bkf_pde_options_default();
    bkf_model_params model = {2, 0.3, 1.2, 20, 64, BKF_MODEL_CONTINUUM};
    CHECK_STATUS(bkf_init_parse("front:n=2", &sp, &e), BKF_OK);
    CHECK_STATUS(bkf_init_check(&sp, &model, 1, &o, &e), BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "--init front needs a limit cycle: --nu"), "%s", e.message);
    bkf_init_free(&sp);
    model.nu = -0.96;
    CHECK_STATUS(bkf_init_parse("oscillation:j=32", &sp, &e), BKF_OK);
    CHECK_STATUS(bkf_init_check(&sp, &model, 1, &o, &e), BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "mode j = 32") && strstr(e.message, "N/2 = 32"), "%s", e.message);
    bkf_init_free(&sp);
    CHECK_STATUS(bkf_init_parse("uniform", &sp, &e), BKF_OK);
    model.nu = 3; /* uniform needs no cycle */
    CHECK_STATUS(bkf_init_check(&sp, &model, 1, &o, &e), BKF_OK);
    bkf_init_free(&sp);
}

/* The front seed through bkf_seed_front takes the speeds solver's root: v
 * as bkf_speeds_find gives it (and the paper's n = 7 value), and the same
 * field as bkf_pde_init_front given that root's v and mu. */
TEST(init_seed_front_takes_the_speeds_root)
{
    bkf_model_params model = {2, 0.3, -0.96, 20, 256, BKF_MODEL_CONTINUUM};
    bkf_pde_options o = bkf_pde_options_default();
    bkf_error e;
    bkf_speeds_options so = bkf_speeds_options_default();
    so.tol = 1e-12;
    so.n_from = so.n_to = 7;
    bkf_speeds_table tab;
    memset(&tab, 0, sizeof tab);
    bkf_model_params sm = model;
    sm.N = 0;
    CHECK_STATUS(bkf_speeds_find(&sm, &so, &tab, &e), BKF_OK);
    CHECK(tab.count >= 1);
    bkf_speeds_root root = tab.roots[0];
    size_t count = tab.count;
    bkf_speeds_table_free(&tab);

    bkf_pde *a = bkf_pde_alloc(&model, &o, &e), *b = bkf_pde_alloc(&model, &o, &e);
    CHECK(a && b);
    bkf_pde_front_spec fs = bkf_pde_front_spec_default();
    fs.n = 7;
    bkf_pde_front_info fi;
    CHECK_STATUS(bkf_seed_front(a, &fs, &fi, NULL, &e), BKF_OK);
    CHECK(fi.v == root.v && fi.mu == root.mu && fi.v_err == root.v_err);
    CHECK(fi.roots_for_n == count);
    CHECK_CLOSE(fi.v, 0.347551274998819, 1e-9, 0);
    CHECK(fabs(fi.residual) < 1e-8); /* seven wavelengths fill S */
    bkf_pde_wave w = {7, root.v, root.mu, -1, 0.0, 1, 1e-12};
    bkf_pde_front_info wi;
    CHECK_STATUS(bkf_pde_init_front(b, &w, &wi, NULL, &e), BKF_OK);
    CHECK(isnan(wi.v_err) && wi.roots_for_n == 0 && wi.T == fi.T);
    CHECK(memcmp(bkf_pde_psi(a), bkf_pde_psi(b), 256 * sizeof(double)) == 0);
    CHECK(memcmp(bkf_pde_eta(a), bkf_pde_eta(b), 256 * sizeof(double)) == 0);
    /* more fronts than the speed condition allows */
    fs.n = 99;
    CHECK_STATUS(bkf_seed_front(a, &fs, NULL, NULL, &e), BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "no front speed for n = 99"), "%s", e.message);
    /* a front spec goes through the same seed */
    bkf_init_spec sp;
    CHECK_STATUS(bkf_init_parse("front:n=7", &sp, &e), BKF_OK);
    CHECK_STATUS(bkf_seed_init(b, &sp, &wi, NULL, &e), BKF_OK);
    CHECK(wi.v == root.v && wi.roots_for_n == count);
    CHECK_STATUS(bkf_init_apply(b, &sp, &e), BKF_EINPUT); /* needs the solver */
    bkf_init_free(&sp);
    bkf_pde_free(a);
    bkf_pde_free(b);
}

/* The default front level is the middle of the cycle's range at mu =
 * gamma (from bkf_cycle_period here), nu without a cycle. */
TEST(init_front_level_is_the_cycle_middle)
{
    const double nus[] = {-0.96, -0.5, 0.3};
    for (size_t i = 0; i < 3; i++) {
        bkf_model_params m = {2, 0.3, nus[i], 20, 0, BKF_MODEL_CONTINUUM};
        bkf_cycle_options co = bkf_cycle_options_default();
        bkf_cycle_result cr;
        bkf_error e;
        CHECK_STATUS(bkf_cycle_period(2, nus[i], &co, &cr, &e), BKF_OK);
        double period;
        double level = bkf_measure_front_level(&m, &period);
        CHECK_CLOSE(level, 0.5 * (cr.xmin + cr.xmax), 0, 1e-12);
        CHECK_CLOSE(period, cr.period, 1e-12, 0);
        CHECK(level != nus[i]);
    }
    bkf_model_params slip = {2, 0.3, -1.2, 20, 0, BKF_MODEL_CONTINUUM};
    double period = -1;
    CHECK(bkf_measure_front_level(&slip, &period) == -1.2 && period == 0);
    CHECK(bkf_measure_front_level(&slip, NULL) == -1.2);
}

TEST(init_sampling_and_snapshots)
{
    bkf_init_sampling s;
    bkf_error e;
    CHECK_STATUS(bkf_init_sampling_plan(20, 500, 0.1, &s, &e), BKF_OK);
    CHECK(s.per_frame == 1 && s.sample_dt == 20.0 / 500);
    CHECK_STATUS(bkf_init_sampling_plan(125, 500, 0.1, &s, &e), BKF_OK); /* frames of 0.25 */
    CHECK(s.per_frame == 3 && s.sample_dt == 0.25 / 3);
    CHECK_STATUS(bkf_init_sampling_plan(50, 500, 0.1, &s, &e), BKF_OK); /* exactly 0.1 */
    CHECK(s.per_frame == 1);
    CHECK_STATUS(bkf_init_sampling_plan(0, 500, 0.1, &s, &e), BKF_EINPUT);
    CHECK_STATUS(bkf_init_sampling_plan(1, 0, 0.1, &s, &e), BKF_EINPUT);
    CHECK_STATUS(bkf_init_sampling_plan(1, 5, NAN, &s, &e), BKF_EINPUT);
    CHECK(bkf_init_snapshot_frame(0, 3, 50) == 0 && bkf_init_snapshot_frame(1, 3, 50) == 25 &&
          bkf_init_snapshot_frame(2, 3, 50) == 50);
    CHECK(bkf_init_snapshot_frame(0, 1, 50) == 50);
    CHECK(bkf_init_snapshot_frame(1, 4, 10) == 3 && bkf_init_snapshot_frame(2, 4, 10) == 7);
}

/* A run that spends its step budget is BKF_EBUDGET, one that blows up
 * BKF_EBLOWUP. */
TEST(init_run_status_codes)
{
    bkf_model_params model = {2, 0.3, -0.96, 20, 32, BKF_MODEL_CONTINUUM};
    bkf_pde_options o = bkf_pde_options_default();
    o.max_steps = 3;
    bkf_error e;
    bkf_pde *m = bkf_pde_alloc(&model, &o, &e);
    CHECK(m != NULL);
    CHECK_STATUS(bkf_pde_init_uniform(m, 0.1, 1, &e), BKF_OK);
    CHECK_STATUS(bkf_pde_run(m, 50, 1, NULL, NULL, NULL, NULL, &e), BKF_EBUDGET);
    CHECK_MSG(strstr(e.message, "more than 3 steps"), "%s", e.message);
    bkf_pde_free(m);
    /* psi = 1e5: psi_t ~ -gamma psi^3/3 runs away from any explicit step */
    o.max_steps = 0;
    o.tol = 1e-2;
    m = bkf_pde_alloc(&model, &o, &e);
    double psi[32], eta[32];
    for (int i = 0; i < 32; i++) {
        psi[i] = i % 2 ? 1e5 : -1e5;
        eta[i] = 1e6;
    }
    CHECK_STATUS(bkf_pde_set_state(m, psi, eta, 0, &e), BKF_OK);
    int s = bkf_pde_run(m, 10, 1, NULL, NULL, NULL, NULL, &e);
    CHECK_MSG(s == BKF_EBLOWUP, "status %d: %s", s, e.message);
    bkf_pde_free(m);
}

/* A state file is read within bounds: /dev/zero (NUL bytes) and an overlong
 * line stop at once, an endless stream of comment lines stops at the byte
 * budget of its rows (128 per row + 1 MiB), each with a message that says
 * which limit; a file within them reads. */
TEST(init_state_reader_is_bounded)
{
    bkf_io_state st;
    bkf_error e = {0};
    FILE *z = fopen("/dev/zero", "r");
    CHECK(z);
    CHECK_STATUS(bkf_io_read_state(z, 1000, &st, &e), BKF_EINPUT);
    fclose(z);
    CHECK_MSG(strstr(e.message, "NUL byte"), "%s", e.message);
    CHECK(st.rows == 0 && !st.psi);

    char *long_line = malloc(5000);
    CHECK(long_line);
    memset(long_line, '1', 4999);
    long_line[4999] = '\0';
    char *text = malloc(6000);
    CHECK(text);
    snprintf(text, 6000, "psi\teta\n%s\t1\n", long_line);
    CHECK_STATUS(read_text(text, 1000, &st, &e), BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "line 2 is longer than 4096 bytes"), "%s", e.message);

    /* 2 MiB of comments against a budget of 10 rows: 1 MiB + 1280 bytes */
    FILE *f = tmpfile();
    CHECK(f);
    for (int i = 0; i < (1 << 20); i++) fputs("#\n", f);
    fputs("psi\teta\n", f);
    for (int i = 0; i < 8; i++) fputs("0\t0\n", f);
    rewind(f);
    CHECK_STATUS(bkf_io_read_state(f, 10, &st, &e), BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "larger than 1049856 bytes (the limit for 10 rows)"), "%s",
              e.message);
    /* the same rows after 512 KiB of comments are within the budget */
    rewind(f);
    CHECK(ftruncate(fileno(f), 0) == 0);
    for (int i = 0; i < (1 << 18); i++) fputs("#\n", f);
    fputs("psi\teta\n", f);
    for (int i = 0; i < 8; i++) fprintf(f, "%d\t0\n", i);
    rewind(f);
    CHECK_STATUS(bkf_io_read_state(f, 10, &st, &e), BKF_OK);
    CHECK(st.rows == 8 && st.psi[7] == 7);
    bkf_io_state_free(&st);
    fclose(f);
    free(text);
    free(long_line);
}

/* oscillation,noise=E is the clean oscillation plus the very noise of
 * uniform:amp=E with the same seed (its rms E, eta untouched), at any N;
 * another seed draws other noise. */
TEST(init_oscillation_plus_noise_is_the_oscillation_plus_uniform_noise)
{
    bkf_error e;
    for (size_t N = 64; N <= 128; N *= 2) {
        bkf_model_params model = {2, 0.3, -0.94, 20, N, BKF_MODEL_CONTINUUM};
        bkf_pde_options o = bkf_pde_options_default();
        bkf_pde *clean = bkf_pde_alloc(&model, &o, &e), *noisy = bkf_pde_alloc(&model, &o, &e),
                *uni = bkf_pde_alloc(&model, &o, &e), *other = bkf_pde_alloc(&model, &o, &e);
        CHECK(clean && noisy && uni && other);
        const char *specs[] = {"oscillation:j=1,amp=0.01", "oscillation:j=1,amp=0.01,noise=0.05",
                               "uniform:amp=0.05", "oscillation:j=1,amp=0.01,noise=0.05"};
        bkf_pde *pdes[] = {clean, noisy, uni, other};
        for (int k = 0; k < 4; k++) {
            bkf_init_spec sp;
            CHECK_STATUS(bkf_init_parse(specs[k], &sp, &e), BKF_OK);
            sp.seed = k == 3 ? 8 : 7;
            CHECK_STATUS(bkf_init_check(&sp, &model, 1, &o, &e), BKF_OK);
            CHECK_STATUS(bkf_init_apply(pdes[k], &sp, &e), BKF_OK);
            bkf_init_free(&sp);
        }
        double sq = 0, diff_other = 0;
        for (size_t i = 0; i < N; i++) {
            double added = bkf_pde_psi(noisy)[i] - bkf_pde_psi(clean)[i];
            CHECK_CLOSE(added, bkf_pde_psi(uni)[i] - model.nu, 0, 1e-15);
            CHECK(bkf_pde_eta(noisy)[i] == bkf_pde_eta(clean)[i]);
            sq += added * added;
            diff_other += fabs(bkf_pde_psi(other)[i] - bkf_pde_psi(noisy)[i]);
        }
        CHECK_CLOSE(sqrt(sq / (double)N), 0.05, 1e-12, 0);
        CHECK(diff_other > 1e-3 * (double)N);
        bkf_pde_free(clean);
        bkf_pde_free(noisy);
        bkf_pde_free(uni);
        bkf_pde_free(other);
    }
    bkf_init_spec sp;
    CHECK_STATUS(bkf_init_parse("oscillation:noise=11", &sp, &e), BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "--init oscillation noise") && strstr(e.message, "[0, 10]"), "%s",
              e.message);
    bkf_init_free(&sp);
}
