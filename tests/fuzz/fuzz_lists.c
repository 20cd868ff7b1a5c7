/* libFuzzer target: the list grammar of every product (bkf_list_parse:
 * "V1,V2,...", A:B:N, linear or geometric) and the fit ranges of the
 * asymptotics product (--mu of --fit: an A:B:N checked by bkf_approx_check).
 * The first byte picks: bit 0 the parser, bit 1 a geometric list. */
#include "fuzz_common.h"

#include <math.h>

#include "bkfront/approx.h"
#include "bkfront/cycle.h"
#include "bkfront/options.h"

static void apply(bkf_approx_spec *spec, const char *key, const char *text, bkf_error *e)
{
    const bkf_option *o = bkf_option_find(bkf_approx_options, bkf_approx_noptions, key);
    FUZZ_CHECK(o);
    int s = bkf_option_apply(o, spec, text, "--", e);
    fuzz_check_status(s, e);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1) return 0;
    char *text = fuzz_string(data + 1, size - 1);
    bkf_error e = {0};
    if (data[0] & 1) {
        int geometric = (data[0] & 2) != 0;
        bkf_list list;
        int s = bkf_list_parse(text, geometric, 0, 0, "--", "nu", &list, &e);
        fuzz_check_status(s, &e);
        if (s == BKF_OK) {
            FUZZ_CHECK(list.values && list.count >= 1 && list.count <= BKF_LIST_MAX);
            FUZZ_CHECK(list.from == list.values[0] && list.to == list.values[list.count - 1]);
            for (size_t i = 0; i < list.count; i++) {
                FUZZ_CHECK(isfinite(list.values[i]));
                FUZZ_CHECK(!geometric || list.values[i] > 0);
            }
            /* a comma list has one value per comma-separated item */
            if (strchr(text, ',')) {
                size_t items = 1;
                for (const char *p = text; *p; p++) items += *p == ',';
                FUZZ_CHECK(list.count == items);
            }
        } else
            FUZZ_CHECK(!list.values && list.count == 0);
        bkf_list_free(&list);
    } else {
        bkf_approx_spec spec = bkf_approx_spec_default();
        spec.fit = 1;
        apply(&spec, "nu", "0", &e);
        apply(&spec, "mu", text, &e);
        int s = bkf_approx_check(&spec, "--", &e);
        fuzz_check_status(s, &e);
        /* what bkf_asymfit_large accepts */
        if (s == BKF_OK && spec.mu.count)
            FUZZ_CHECK(spec.mu.from >= 1 && spec.mu.from < spec.mu.to &&
                       spec.mu.to <= BKF_CYCLE_MU_MAX && spec.mu.count >= 10);
        bkf_approx_spec_free(&spec);
    }
    free(text);
    return 0;
}
