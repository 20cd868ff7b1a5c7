/* The lazy loader (src/core/lazylib.c): what it says when a library or a
 * symbol is missing, and that libbkfront.a defines none of LAPACKE's or
 * ARPACK's names (a program linking the real static liblapacke beside it
 * must link).  The CLI's behaviour without each library:
 * tests/cli/test_cli_start.c. */
#define _DEFAULT_SOURCE
#include "harness.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "../../src/core/lazylib_internal.h"

#ifndef BKF_LIBRARY_ARCHIVE
#error "BKF_LIBRARY_ARCHIVE, BKF_TEST_LDFLAGS and BKF_TEST_LDLIBS are defined by the Makefile for tests"
#endif

TEST(lazy_open_names_the_missing_library_or_symbol)
{
    bkf_error e;
    void *out[2] = {&e, &e};
    const char *const names[] = {"cos", "bkf_no_such_symbol"};
    CHECK_STATUS(bkf_lazy_open("libbkf_no_such.so.9", "bkf-nothing", names, out, 1, &e), BKF_EIO);
    CHECK_MSG(strstr(e.message, "libbkf_no_such.so.9 does not load: ") &&
              strstr(e.message, "(Debian: apt-get install bkf-nothing)"), "%s", e.message);
    CHECK(out[0] == NULL);
    /* a library that loads but lacks one symbol: none is returned */
    out[0] = out[1] = &e;
    CHECK_STATUS(bkf_lazy_open("libm.so.6", "libc6", names, out, 2, &e), BKF_EIO);
    CHECK_MSG(strstr(e.message, "libm.so.6 has no symbol bkf_no_such_symbol"), "%s", e.message);
    CHECK(out[0] == NULL && out[1] == NULL);
    CHECK_STATUS(bkf_lazy_open("libm.so.6", "libc6", names, out, 1, &e), BKF_OK);
    double (*cosine)(double) = (double (*)(double))out[0];
    CHECK(cosine && cosine(0.0) == 1.0 && fabs(cosine(M_PI) + 1.0) < 1e-15);
}

/* A program of the user's that calls the real LAPACKE_zgeev from the static
 * liblapacke.a and a function of libbkfront.a's lazylib.o: with lazylib.o
 * defining LAPACKE_zgeev itself (before bkf_LAPACKE_zgeev) the link failed,
 * "multiple definition of `LAPACKE_zgeev'".  It runs, and its zgeev is
 * LAPACK's: the eigenvalues of the rotation [0 1; -1 0] are +-i. */
TEST(lazy_static_link_beside_the_real_liblapacke)
{
    if (access("/usr/lib/x86_64-linux-gnu/liblapacke.a", R_OK) != 0 &&
        system("cc -print-file-name=liblapacke.a | grep -q /") != 0) {
        bkf_test_note("skipped: no static liblapacke.a");
        return;
    }
    char dir[] = "/tmp/bkf_lazylink_XXXXXX";
    CHECK(mkdtemp(dir) != NULL);
    char cmd[4096];
    snprintf(cmd, sizeof cmd,
             "T=%s; cat > \"$T/p.c\" <<'END'\n"
             "#include <complex.h>\n#include <lapacke.h>\n#include <math.h>\n#include <stdio.h>\n"
             "#include \"bkfront/lazylib.h\"\n"
             "int main(void)\n{\n"
             "    lapack_complex_double a[4] = {0, -1, 1, 0}, w[2];\n"
             "    lapack_int info = LAPACKE_zgeev(LAPACK_COL_MAJOR, 'N', 'N', 2, a, 2, w, NULL, 1, NULL, 1);\n"
             "    printf(\"%%d %%.3f %%.3f %%s\", (int)info, fabs(creal(w[0])), fabs(cimag(w[0])),\n"
             "           bkf_lazy_failure() ? \"failed\" : \"none\");\n"
             "    return info != 0;\n}\n"
             "END\n"
             "cc -std=c11 -Wall -Werror -I'%s/include' $(pkg-config --cflags lapacke) -c \"$T/p.c\" "
             "-o \"$T/p.o\" && cc %s -o \"$T/p\" \"$T/p.o\" -Wl,-Bstatic -llapacke -llapack -lblas "
             "-Wl,-Bdynamic '%s' %s -lgfortran > \"$T/link.log\" 2>&1 && \"$T/p\" > \"$T/out\"; "
             "rc=$?; cat \"$T/link.log\" \"$T/out\"; exit $rc",
             dir, BKF_SOURCE_DIR, BKF_TEST_LDFLAGS, BKF_LIBRARY_ARCHIVE, BKF_TEST_LDLIBS);
    FILE *p = popen(cmd, "r");
    CHECK(p != NULL);
    char out[2048] = "";
    size_t n = fread(out, 1, sizeof out - 1, p);
    out[n] = '\0';
    int st = pclose(p);
    char rm[96];
    snprintf(rm, sizeof rm, "rm -rf '%s'", dir);
    CHECK(system(rm) == 0);
    CHECK_MSG(WIFEXITED(st) && WEXITSTATUS(st) == 0, "link or run failed:\n%s", out);
    CHECK_MSG(strcmp(out, "0 0.000 1.000 none") == 0, "output: %s", out);
}
