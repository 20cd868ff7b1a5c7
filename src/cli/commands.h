/* The table of subcommands: used by main for dispatch and by `bkfront run`,
 * which carries out a scene's products with the same subcommands. */
#ifndef BKFRONT_CLI_COMMANDS_H
#define BKFRONT_CLI_COMMANDS_H

#include <stddef.h>
#include "args.h"

size_t cli_command_count(void);
const cli_command *cli_command_at(size_t i);
/* NULL when there is no such subcommand. */
const cli_command *cli_find_command(const char *name);

#endif
