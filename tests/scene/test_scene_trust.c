/* The plan's trust (bkf_scene_plan_options.trust) covers a figure's own
 * script: gnuplot's system() and shell escapes run anything, so a library
 * caller that does not trust a scene gets the refusal bkfront run gives
 * without --trust-scene, at the key's line. */
#include "harness.h"

#include <string.h>

#include "bkfront/scene.h"

static const char own_script[] = "[model]\ngamma = 2\nc = 0.3\nnu = -0.96\nS = 20\n\n"
                                 "[friction f]\nfrom = -1\nto = 3\n"
                                 "[figure f]\ndata = f\nscript = own.gp\n";

static int plan_status(const char *text, int figures, int trust, bkf_error *e)
{
    bkf_scene *sc = NULL;
    int s = bkf_scene_parse_string(text, "t.scene", &sc, e);
    if (s) return -1;
    bkf_scene_plan plan;
    bkf_scene_plan_options o = {.outdir = "out", .figures = figures, .trust = trust};
    s = bkf_scene_make_plan(sc, &o, &plan, e);
    if (!s) bkf_scene_plan_free(&plan);
    bkf_scene_free(sc);
    return s;
}

TEST(scene_plan_runs_a_scene_s_own_script_only_when_trusted)
{
    bkf_error e;
    CHECK_STATUS(plan_status(own_script, 1, 0, &e), BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "t.scene:12: script = own.gp") == e.message &&
                  strstr(e.message, "--trust-scene"),
              "%s", e.message);
    CHECK_STATUS(plan_status(own_script, 1, 1, &e), BKF_OK);
    /* without figures nothing runs the script */
    CHECK_STATUS(plan_status(own_script, 0, 0, &e), BKF_OK);
    /* the plots' own scripts need no trust */
    const char *plain = "[model]\ngamma = 2\nc = 0.3\nnu = -0.96\nS = 20\n\n"
                        "[friction f]\nfrom = -1\nto = 3\n[figure f]\ndata = f\n";
    CHECK_STATUS(plan_status(plain, 1, 0, &e), BKF_OK);
}
