/* libFuzzer target: the scene-file (INI) parser, bkf_scene_parse_string
 * (bkfront/scene.h), and the plan made from what it accepts.  A parsed
 * scene must plan and free cleanly; a rejection must follow the error
 * contract (one line, no control characters). */
#include "fuzz_common.h"

#include <stdlib.h>

#include "bkfront/scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *text = fuzz_string(data, size);
    bkf_scene *sc = NULL;
    bkf_error e = {0};
    int s = bkf_scene_parse_string(text, "fuzz.scene", &sc, &e);
    fuzz_check_status(s, &e);
    if (s == BKF_OK) {
        FUZZ_CHECK(sc != NULL);
        bkf_scene_plan plan;
        bkf_scene_plan_options o = {.outdir = "out", .formats = 7, .figures = 1};
        int p = bkf_scene_make_plan(sc, &o, &plan, &e);
        FUZZ_CHECK(p == BKF_OK || p == BKF_ENOMEM);
        if (p == BKF_OK) {
            for (size_t i = 0; i < plan.nsteps; i++) {
                FUZZ_CHECK(plan.steps[i].nusers >= 1);
                char *cmd = bkf_scene_step_command(&plan.steps[i]);
                free(cmd);
            }
            bkf_scene_plan_free(&plan);
        }
    }
    bkf_scene_free(sc);
    free(text);
    return 0;
}
