/* The friction product: its rows against the closed forms of model.h
 * (phi(psi) = psi^3/3 - psi, Carlson-Langer sgn(v)/(1 + |v|)) written out
 * here, and the scene's friction kind writes the library's table. */
#include "products_support.h"

#include <math.h>
#include <unistd.h>

#include "bkfront/friction.h"

static int write_friction(const void *spec, FILE *out, bkf_io_format format,
                          const bkf_provenance *prov, bkf_error *err)
{
    return bkf_friction_table(spec, out, format, prov, err);
}

TEST(products_friction_rows_are_the_closed_forms)
{
    bkf_friction_spec s = bkf_friction_spec_default();
    s.points = 11; /* v = -1, -0.5, 0, ..., 4: v = 0 is a row */
    char *tsv = library_output(write_friction, &s, BKF_IO_TSV);
    char *body = table_body(tsv);
    CHECK_MSG(strncmp(body, "v\tpsi\tcreep_slip\tcarlson_langer\n", 32) == 0, "%s", body);
    const char *line = strchr(body, '\n') + 1;
    size_t rows = 0;
    for (; *line; line = strchr(line, '\n') + 1, rows++) {
        char *end;
        double v = strtod(line, &end), psi = strtod(end, &end), creep = strtod(end, &end),
               cl = strtod(end, &end);
        double want_v = -1 + 0.5 * (double)rows;
        CHECK_CLOSE(v, want_v, 0, 1e-15);
        CHECK_CLOSE(psi, v - 1, 0, 1e-15);
        CHECK_CLOSE(creep, 1.5 * (psi * psi * psi / 3 - psi), 1e-15, 1e-15);
        if (v == 0)
            CHECK_MSG(isnan(cl), "Carlson-Langer at v = 0: %g, want the gap (nan)", cl);
        else
            CHECK_CLOSE(cl, (v > 0 ? 1 : -1) / (1 + fabs(v)), 1e-15, 0);
    }
    CHECK(rows == 11);
    /* the laws' landmarks: static friction 1 at v = 0 (psi = -1), the
     * minimum -1 of creep_slip at psi = 1 (v = 2) */
    CHECK_CLOSE(bkf_friction_at(0).creep_slip, 1, 1e-15, 0);
    CHECK_CLOSE(bkf_friction_at(2).creep_slip, -1, 1e-15, 0);
    free(body);
    free(tsv);
    bkf_error e;
    s.to = s.from;
    CHECK_STATUS(bkf_friction_check(&s, "", &e), BKF_EINPUT);
}

TEST(products_friction_scene_writes_the_library_table)
{
    char dir[] = "/tmp/bkf_products_friction_XXXXXX";
    CHECK(mkdtemp(dir));
    char scene[512], out[512], args[1200];
    snprintf(scene, sizeof scene, "%s/fr.scene", dir);
    snprintf(out, sizeof out, "%s/out", dir);
    FILE *f = fopen(scene, "w");
    CHECK(f);
    fprintf(f, "[model]\ngamma = 2\nc = 0.3\nnu = -0.96\nS = 20\n[friction laws]\nfrom = -2\n"
               "to = 3\npoints = 41\n");
    CHECK(fclose(f) == 0);
    snprintf(args, sizeof args, "run --no-figures --out %s %s", out, scene);
    free(cli_output(args));
    char path[600];
    snprintf(path, sizeof path, "%s/laws.tsv", out);
    f = fopen(path, "r");
    CHECK_MSG(f, "%s missing", path);
    char file[1 << 14];
    size_t n = fread(file, 1, sizeof file - 1, f);
    file[n] = '\0';
    fclose(f);
    bkf_friction_spec s = {-2, 3, 41};
    char *lib = library_output(write_friction, &s, BKF_IO_TSV);
    /* the scene's table is the library's, with its provenance (the
     * equivalent command line, as every scene table) */
    CHECK_MSG(strcmp(table_body(lib), table_body(file)) == 0,
              "scene file differs from the library's table");
    CHECK_MSG(strstr(file, "# command: bkfront friction --from -2 --to 3 --points 41 --out "),
              "no provenance: %.200s", file);
    free(lib);
    unlink(path);
    rmdir(out);
    unlink(scene);
    rmdir(dir);
}
