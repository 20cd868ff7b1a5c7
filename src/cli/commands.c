/* The subcommand table (commands.h).  Adding a subcommand is an extern
 * declaration and an entry below. */
#include "commands.h"

#include <string.h>

extern const cli_command cli_cmd_period;
extern const cli_command cli_cmd_asymptotics;
extern const cli_command cli_cmd_floquet;
extern const cli_command cli_cmd_orbit;
extern const cli_command cli_cmd_speeds;
extern const cli_command cli_cmd_branch;
extern const cli_command cli_cmd_stability;
extern const cli_command cli_cmd_profile;
extern const cli_command cli_cmd_simulate;
extern const cli_command cli_cmd_check;
extern const cli_command cli_cmd_run;
extern const cli_command cli_cmd_bench;
extern const cli_command cli_cmd_friction;
extern const cli_command cli_cmd_sweep;

static const cli_command *const commands[] = {
    &cli_cmd_period,
    &cli_cmd_asymptotics,
    &cli_cmd_speeds,
    &cli_cmd_branch,
    &cli_cmd_stability,
    &cli_cmd_profile,
    &cli_cmd_floquet,
    &cli_cmd_orbit,
    &cli_cmd_friction,
    &cli_cmd_simulate,
    &cli_cmd_check,
    &cli_cmd_sweep,
    &cli_cmd_run,
    &cli_cmd_bench,
};

#define NCOMMANDS (sizeof commands / sizeof commands[0])

size_t cli_command_count(void)
{
    return NCOMMANDS;
}

const cli_command *cli_command_at(size_t i)
{
    return i < NCOMMANDS ? commands[i] : NULL;
}

const cli_command *cli_find_command(const char *name)
{
    for (size_t i = 0; name && i < NCOMMANDS; i++)
        if (strcmp(commands[i]->name, name) == 0) return commands[i];
    return NULL;
}
