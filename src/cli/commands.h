/* The table of subcommands: used by main for dispatch and by `bkfront run`,
 * which carries out a scene's products with the same subcommands. */
#ifndef BKFRONT_CLI_COMMANDS_H
#define BKFRONT_CLI_COMMANDS_H

#include <stddef.h>
#include "args.h"
#include "bkfront/catalog.h"

size_t cli_command_count(void);
const cli_command *cli_command_at(size_t i);
/* NULL when there is no such subcommand. */
const cli_command *cli_find_command(const char *name);

/* A catalogue product (catalog.h) run from flags: its option table and the
 * output flags, its check, its table written all or nothing. */
int cli_run_product(const char *name, int argc, char **argv, bkf_error *err);
/* The same, with hooks for the product (its warnings, say; NULL: none). */
int cli_run_product_hooks(const char *name, const bkf_catalog_hooks *hooks, int argc,
                          char **argv, bkf_error *err);
void cli_product_help(const char *name, FILE *out);
/* The options part of its help: its keys, then the output flags (a command
 * with a help text of its own, cmd_period.c). */
void cli_product_options_help(const char *name, FILE *out);

#endif
