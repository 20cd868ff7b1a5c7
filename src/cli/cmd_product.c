/* A catalogue product as a subcommand (commands.h): its keys are the flags,
 * its summary the help's first line, the output flags shared by all. */
#include "commands.h"

#include <stdlib.h>

#include "bkfront/catalog.h"

static int write_entry(const void *data, FILE *out, bkf_io_format format,
                       const bkf_provenance *prov, bkf_error *err)
{
    const void *const *pair = data; /* entry, spec */
    const bkf_catalog_entry *entry = pair[0];
    return entry->write(pair[1], out, format, prov, NULL, err);
}

int cli_run_product(const char *name, int argc, char **argv, bkf_error *err)
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
    const void *pair[2] = {entry, spec};
    if (!s) s = cli_write_table(&output, argc, argv, write_entry, pair, err);
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
