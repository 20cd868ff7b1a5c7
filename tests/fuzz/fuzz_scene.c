/* libFuzzer target: the scene-file (INI) parser, scene_parse_string
 * (src/cli/scene.h), and the plan made from what it accepts.  The parser
 * lives in the CLI, so its source is included here (args.o is linked).  A
 * parsed scene must plan and free cleanly; a rejection must follow the
 * error contract (one line, no control characters). */
#include "fuzz_common.h"

#include "../../src/cli/scene.c"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *text = fuzz_string(data, size);
    scene *sc = NULL;
    bkf_error e = {0};
    int s = scene_parse_string(text, "fuzz.scene", &sc, &e);
    fuzz_check_status(s, &e);
    if (s == BKF_OK) {
        FUZZ_CHECK(sc != NULL);
        scene_plan plan;
        scene_plan_options o = {.outdir = "out", .formats = 7, .figures = 1};
        int p = scene_make_plan(sc, &o, &plan, &e);
        FUZZ_CHECK(p == BKF_OK || p == BKF_ENOMEM);
        if (p == BKF_OK) {
            for (size_t i = 0; i < plan.nsteps; i++) {
                FUZZ_CHECK(plan.steps[i].nusers >= 1);
                char *cmd = scene_step_command(&plan.steps[i]);
                free(cmd);
            }
            scene_plan_free(&plan);
        }
    }
    scene_free(sc);
    free(text);
    return 0;
}
