/* libFuzzer target: the user-text parsers of `bkfront simulate`, through the
 * library: the --init specification (bkf_init_parse: uniform/oscillation/
 * front key=value lists) and the state file read by --init file:PATH
 * (bkf_io_read_state: a TSV naming psi and eta).
 *
 * The first byte picks the parser; the state file is read from memory
 * (fmemopen); bkf_init_parse reads no file, so every spec is parsed. */
#include "fuzz_common.h"

#include <math.h>

#include "bkfront/init.h"
#include "bkfront/io.h"

static void fuzz_spec(const char *text)
{
    bkf_init_spec p;
    bkf_error e = {0};
    int s = bkf_init_parse(text, &p, &e);
    fuzz_check_status(s, &e);
    if (s == BKF_OK) {
        FUZZ_CHECK(p.amp >= 0 && p.amp <= 10);
        if (p.kind == BKF_INIT_OSCILLATION && p.q_given) FUZZ_CHECK(p.q >= 0 && isfinite(p.q));
        if (p.kind == BKF_INIT_FRONT) {
            FUZZ_CHECK(p.front.n >= 1 && p.front.n <= 100000);
            FUZZ_CHECK(p.front.root >= 1 && p.front.root <= 100);
            FUZZ_CHECK(p.front.direction == -1 || p.front.direction == 1);
            FUZZ_CHECK(p.front.noise >= 0 && p.front.noise <= 10);
        }
        if (p.kind == BKF_INIT_FILE) FUZZ_CHECK(p.path && *p.path && !p.state.psi);
        else FUZZ_CHECK(p.kind == BKF_INIT_UNIFORM || p.kind == BKF_INIT_OSCILLATION ||
                        p.kind == BKF_INIT_FRONT);
    }
    bkf_init_free(&p);
}

static void fuzz_state_file(const uint8_t *data, size_t size)
{
    if (size == 0) return;
    /* a private copy: fmemopen's buffer is not const */
    char *copy = malloc(size);
    if (!copy) abort();
    memcpy(copy, data, size);
    FILE *f = fmemopen(copy, size, "r");
    if (!f) {
        free(copy);
        return;
    }
    bkf_io_state st;
    bkf_error e = {0};
    int s = bkf_io_read_state(f, 1 << 16, &st, &e);
    fclose(f);
    fuzz_check_status(s, &e);
    if (s == BKF_OK) {
        FUZZ_CHECK(st.rows == 0 || (st.psi && st.eta));
        for (size_t i = 0; i < st.rows; i++) FUZZ_CHECK(isfinite(st.psi[i]) && isfinite(st.eta[i]));
    } else
        FUZZ_CHECK(!st.psi && !st.eta && st.rows == 0);
    bkf_io_state_free(&st);
    free(copy);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1) return 0;
    if (data[0] & 1) {
        fuzz_state_file(data + 1, size - 1);
    } else {
        char *text = fuzz_string(data + 1, size - 1);
        fuzz_spec(text);
        free(text);
    }
    return 0;
}
