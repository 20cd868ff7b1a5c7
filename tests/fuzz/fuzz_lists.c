/* libFuzzer target: the list and fit-range parsers of `bkfront asymptotics`
 * (--nu/--eps "V1,V2,..." or A:B:N; --mu/--small-mu geometric fit ranges),
 * static in src/cli/cmd_asymptotics.c, which is included here (the target
 * links args.o and the library, not cmd_asymptotics.o).  The first byte
 * picks the parser. */
#include "fuzz_common.h"

#include "../../src/cli/cmd_asymptotics.c"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1) return 0;
    char *text = fuzz_string(data + 1, size - 1);
    bkf_error e = {0};
    if (data[0] & 1) {
        cli_range list;
        int s = parse_list("--nu", text, &list, &e);
        fuzz_check_status(s, &e);
        if (s == BKF_OK) {
            FUZZ_CHECK(list.values && list.count >= 1 && list.count <= CLI_MAX_POINTS);
            FUZZ_CHECK(list.from == list.values[0] && list.to == list.values[list.count - 1]);
            for (size_t i = 0; i < list.count; i++) FUZZ_CHECK(isfinite(list.values[i]));
            /* a comma list has one value per comma-separated item */
            if (strchr(text, ',')) {
                size_t items = 1;
                for (const char *p = text; *p; p++) items += *p == ',';
                FUZZ_CHECK(list.count == items);
            }
        }
        cli_range_free(&list);
    } else {
        double from = 0, to = 0;
        size_t n = 0;
        int s = parse_fit_range("--mu", text, 1.0, 1e4, 10, &from, &to, &n, &e);
        fuzz_check_status(s, &e);
        if (s == BKF_OK) FUZZ_CHECK(from >= 1 && from < to && to <= 1e4 && n >= 10);
    }
    free(text);
    return 0;
}
