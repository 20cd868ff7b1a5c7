/* bkfront orbit: the branch of period-doubled orbits (bkfront/orbits.h)
 * from flags, with a progress bar; Ctrl-C stops it (nothing written). */
#include <signal.h>

#include "progress.h"

#include "bkfront/orbits.h"

typedef struct {
    bkf_orbits_spec spec;
    cli_progress_spec progress;
    cli_output_spec output;
} orbit_args;

static void groups_of(orbit_args *a, cli_options g[3])
{
    g[0] = (cli_options){bkf_orbits_spec_options, bkf_orbits_spec_noptions, a ? &a->spec : NULL};
    g[1] = (cli_options){cli_progress_options, cli_progress_noptions, a ? &a->progress : NULL};
    g[2] = (cli_options){cli_output_options, cli_output_noptions, a ? &a->output : NULL};
}

static void orbit_help(FILE *out)
{
    cli_options g[3];
    groups_of(NULL, g);
    fprintf(out,
        "usage: bkfront orbit [--gamma G] [--c C] [--S L] [--model continuum|chain] [--N N]\n"
        "                     [--j J] [--from A] [--to B] [--max-points M] [--tol E]\n"
        "       bkfront orbit --along gamma|c|S --nu V --from A --to B [...]\n"
        "   common: [--step H] [--no-stability] [--k K] [--switch-amplitude A]\n"
        "           [--at P] [--spacetime FILE] [--multipliers FILE]\n"
        "           [--regimes SWEEP --coexistence FILE]\n"
        "           [--no-progress] [--format tsv|json] [--out FILE]\n"
        "\n"
        "The period-doubled pacemakers of the paper's Fig. 4(b) as exact solutions: the\n"
        "branch of periodic orbits of the discretised PDE born where the global\n"
        "oscillation's Floquet multiplier for the ring's mode q_j = 2 pi j/S reaches -1\n"
        "(bkfront floquet).  From there the critical eigenvector, cos(q_j x) times the\n"
        "Floquet eigenvector on the doubled cycle, starts the branch; pseudo-arclength\n"
        "continuation follows it in the parameter through folds; every point is solved\n"
        "again to --tol by Newton-Krylov shooting with its error estimate, and judged by\n"
        "its Floquet multipliers (Arnoldi, per Bloch sector).  The period is an unknown:\n"
        "near twice the oscillation's, never set to it.\n"
        "\n"
        "options (defaults: the paper's gamma 2, c 0.3, S 20):\n");
    cli_options_help(out, g, 3);
    fprintf(out,
        "\n"
        "columns:\n"
        "  index, kind       row 0 the bifurcation (the oscillation where its multiplier\n"
        "                    is -1, period 2T), then orbit or fold rows along the branch\n"
        "  nu, gamma, c, S   the parameters of the row\n"
        "  period, period_err  P and the orbit's estimated error (residual + flow + grid)\n"
        "  amplitude         max over one period of max_x psi - min_x psi (400 samples\n"
        "                    of the solved orbit: a description, not a result to tol)\n"
        "  mode_amp          amplitude of cos(q_j x) in psi at t = 0 (the continuation's)\n"
        "  shift             the solved spatial shift (0 for these standing patterns)\n"
        "  verdict           stable, unstable, undecided (by the multipliers and their\n"
        "                    errors), neutral (row 0), none (--no-stability)\n"
        "  m_abs, m_re, m_im, m_err  the largest physical multiplier and its error\n"
        "  out_real_plus, out_real_minus, out_complex  physical multipliers outside the\n"
        "                    unit circle: real > 0, real < 0, complex (im > 0)\n"
        "  events            since the previous row: fold, period_doubling, torus, real,\n"
        "                    stability_change, joined by +; - for none\n"
        "  status            ok, or why the row's numbers are nan (a refused point)\n"
        "\n"
        "Rows are written as they come; output is all or nothing: on any failure, or\n"
        "Ctrl-C (exit 130, 143 for SIGTERM), nothing is written.\n"
        "exit status: 0 ok, 1 numerical failure, 2 bad input\n");
}

static int draw(double fraction, void *data)
{
    progress_draw(fraction, data);
    return 0;
}

static int write_orbits(const void *spec, FILE *out, bkf_io_format format,
                        const bkf_provenance *prov, bkf_error *err)
{
    return bkf_orbits_write(spec, out, format, prov, err);
}

static int orbit_run(int argc, char **argv, bkf_error *err)
{
    orbit_args a = {bkf_orbits_spec_default(), {0}, {0}};
    cli_options g[3];
    groups_of(&a, g);
    int s = cli_parse_options(g, 3, argc, argv, NULL, err);
    if (!s) s = bkf_orbits_check(&a.spec, "--", err);
    if (s) return s;
    progress_bar bar;
    progress_init(&bar, CLI_PROGRAM " orbit", !a.progress.no_progress);
    a.spec.progress = draw;
    a.spec.progress_data = &bar;
    a.spec.cancel = cli_cancel_begin();
    s = cli_write_table(&a.output, argc, argv, write_orbits, &a.spec, err);
    cli_cancel_end();
    progress_end(&bar);
    if (s == BKF_ECANCELED)
        bkf_error_set(err, s, "interrupted (%s): nothing written",
                      cli_cancel_signal() == SIGTERM ? "SIGTERM" : "SIGINT");
    return s;
}

const cli_command cli_cmd_orbit = {
    "orbit",
    "period-doubled pacemakers as exact orbits: their branch from the oscillation, folds, stability",
    orbit_run,
    orbit_help,
};
