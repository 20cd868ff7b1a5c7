/* A catalogue product as a subcommand (commands.h): its keys are the flags,
 * its summary the help's first line, the output flags shared by all. */
#include "commands.h"

#include <stdlib.h>

#include "bkfront/catalog.h"

typedef struct {
    const bkf_catalog_entry *entry;
    const void *spec;
    const bkf_catalog_hooks *hooks;
} product_job;

static int write_entry(const void *data, FILE *out, bkf_io_format format,
                       const bkf_provenance *prov, bkf_error *err)
{
    const product_job *job = data;
    return job->entry->write(job->spec, out, format, prov, job->hooks, err);
}

int cli_run_product(const char *name, int argc, char **argv, bkf_error *err)
{
    return cli_run_product_hooks(name, NULL, argc, argv, err);
}

int cli_run_product_hooks(const char *name, const bkf_catalog_hooks *hooks, int argc,
                          char **argv, bkf_error *err)
{
    const bkf_catalog_entry *entry = bkf_catalog_find(name);
    void *spec = bkf_catalog_spec_new(entry, err);
    if (!spec) return err ? err->status : BKF_ENOMEM;
    cli_output_spec output = {0};
    size_t n;
    const bkf_option *table = entry->options(&n);
    cli_options g[2] = {{table, n, spec}, {cli_output_options, cli_output_noptions, &output}};
    int s = cli_parse_options(g, 2, argc, argv, NULL, err);
    if (!s) s = entry->check(spec, "--", err);
    product_job job = {entry, spec, hooks};
    if (!s) s = cli_write_table(&output, argc, argv, write_entry, &job, err);
    bkf_catalog_spec_free(entry, spec);
    return s;
}

void cli_product_options_help(const char *name, FILE *out)
{
    const bkf_catalog_entry *entry = bkf_catalog_find(name);
    if (!entry) return;
    size_t n;
    const bkf_option *table = entry->options(&n);
    cli_options g[2] = {{table, n, NULL}, {cli_output_options, cli_output_noptions, NULL}};
    cli_options_help(out, g, 2);
}

void cli_product_help(const char *name, FILE *out)
{
    const bkf_catalog_entry *entry = bkf_catalog_find(name);
    if (!entry) return;
    fprintf(out, "usage: bkfront %s [options]\n\n%s.\n\noptions:\n", entry->name, entry->summary);
    cli_product_options_help(name, out);
    fprintf(out, "\nOutput is all or nothing: on any failure nothing is written.\n"
                 "exit status: 0 ok, 1 numerical failure, 2 bad input\n");
}

static int friction_run(int argc, char **argv, bkf_error *err)
{
    return cli_run_product("friction", argc, argv, err);
}

static void friction_help(FILE *out) { cli_product_help("friction", out); }

const cli_command cli_cmd_friction = {
    "friction",
    "the friction laws (creep-slip and Carlson-Langer) sampled against block velocity",
    friction_run,
    friction_help,
};
