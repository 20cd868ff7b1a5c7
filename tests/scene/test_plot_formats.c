/* The one parser of figure format lists (bkf_plot_parse_formats), which a
 * scene's `formats =` and bkfront run --formats share: the bits against the
 * enum, the separators, the refusals and their messages. */
#include "harness.h"

#include <string.h>

#include "bkfront/plot.h"

TEST(scene_plot_formats_parse_to_the_enum_bits)
{
    unsigned f = 0;
    bkf_error e;
    CHECK_STATUS(bkf_plot_parse_formats("png", "", "formats", &f, &e), BKF_OK);
    CHECK(f == 1u << BKF_PLOT_PNG);
    CHECK_STATUS(bkf_plot_parse_formats("svg,pdf", "", "formats", &f, &e), BKF_OK);
    CHECK(f == ((1u << BKF_PLOT_SVG) | (1u << BKF_PLOT_PDF)));
    /* commas, spaces and repeats, as a scene writes them */
    CHECK_STATUS(bkf_plot_parse_formats(" png, svg  png,", "", "formats", &f, &e), BKF_OK);
    CHECK(f == ((1u << BKF_PLOT_PNG) | (1u << BKF_PLOT_SVG)));
    for (int k = 0; k < BKF_PLOT_NFORMATS; k++) {
        CHECK_STATUS(bkf_plot_parse_formats(bkf_plot_format_name((bkf_plot_format)k), "--",
                                            "formats", &f, &e), BKF_OK);
        CHECK(f == 1u << k);
    }
}

TEST(scene_plot_formats_refuse_unknown_and_empty_lists)
{
    unsigned f = 7;
    bkf_error e;
    CHECK_STATUS(bkf_plot_parse_formats("png,jpg", "--", "formats", &f, &e), BKF_EINPUT);
    CHECK_MSG(strcmp(e.message, "--formats: 'jpg' is not one of png, pdf, svg") == 0, "%s",
              e.message);
    CHECK(f == 7); /* untouched on a refusal */
    CHECK_STATUS(bkf_plot_parse_formats(" , ", "", "formats", &f, &e), BKF_EINPUT);
    CHECK_MSG(strcmp(e.message, "formats: give png, pdf or svg") == 0, "%s", e.message);
    CHECK_STATUS(bkf_plot_parse_formats(NULL, "", "formats", &f, &e), BKF_EINPUT);
    CHECK_STATUS(bkf_plot_parse_formats("PNG", "", "formats", &f, &e), BKF_EINPUT);
    /* a long word is refused whole, not cut to a buffer's size */
    char longer[600];
    memset(longer, 'p', sizeof longer - 1);
    longer[sizeof longer - 1] = '\0';
    CHECK_STATUS(bkf_plot_parse_formats(longer, "", "formats", &f, &e), BKF_EINPUT);
}
