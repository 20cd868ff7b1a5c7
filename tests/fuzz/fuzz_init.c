/* libFuzzer target: the user-text parsers of `bkfront simulate`: the --init
 * specification (uniform/oscillation/front key=value lists) and the state
 * file read by --init file:PATH (a TSV naming psi and eta).
 *
 * They are static in src/cli/cmd_simulate.c, so the file is included here
 * (the target links args.o and the library, not cmd_simulate.o).  The first
 * byte picks the parser; the state file is read from memory (fmemopen), and
 * --init specs naming a file are skipped (no file system access). */
#include "fuzz_common.h"

#include "../../src/cli/cmd_simulate.c"

static void fuzz_spec(const char *text)
{
    if (strncmp(text, "file", 4) == 0 && (text[4] == ':' || text[4] == '\0')) return;
    init_plan p;
    bkf_error e = {{0}};
    int s = parse_init(text, &p, &e);
    fuzz_check_status(s, &e);
    if (s == BKF_OK) {
        FUZZ_CHECK(p.kind == INIT_UNIFORM || p.kind == INIT_OSCILLATION || p.kind == INIT_FRONT);
        FUZZ_CHECK(p.amp >= 0 && p.amp <= 10);
        if (p.kind == INIT_OSCILLATION && p.q_given) FUZZ_CHECK(p.q >= 0 && isfinite(p.q));
        if (p.kind == INIT_FRONT) {
            FUZZ_CHECK(p.front.n >= 1 && p.front.n <= 100000);
            FUZZ_CHECK(p.front.root >= 1 && p.front.root <= 100);
            FUZZ_CHECK(p.front.direction == -1 || p.front.direction == 1);
            FUZZ_CHECK(p.front.noise >= 0 && p.front.noise <= 10);
        }
    }
    init_free(&p);
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
    init_plan p;
    memset(&p, 0, sizeof p);
    p.kind = INIT_FILE;
    p.path = "fuzz.tsv";
    bkf_error e = {{0}};
    int s = read_state_stream(&p, f, &e);
    fclose(f);
    fuzz_check_status(s, &e);
    if (s == BKF_OK) {
        FUZZ_CHECK(p.rows >= BKF_PDE_N_MIN && p.psi && p.eta);
        for (size_t i = 0; i < p.rows; i++) FUZZ_CHECK(isfinite(p.psi[i]) && isfinite(p.eta[i]));
    } else
        FUZZ_CHECK(!p.psi && !p.eta);
    init_free(&p);
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
