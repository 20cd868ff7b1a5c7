#include "product_out.h"

#include <stdlib.h>
#include <string.h>

static void warn_stderr(const char *message, void *data)
{
    fprintf(stderr, CLI_PROGRAM " %s: warning: %s\n", (const char *)data, message);
}

int cli_write_product(const char *out_path, bkf_io_format format, cli_product_write write,
                      const void *spec, int argc, char **argv, bkf_error *err)
{
    char *cmd = cli_command_line(argc, argv);
    size_t n = cmd ? strlen(cmd) + 32 : 0;
    char *command = cmd ? malloc(n) : NULL;
    if (!command) {
        free(cmd);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    snprintf(command, n, "command: " CLI_PROGRAM " %s", cmd);
    free(cmd);
    cli_output out = {0};
    cli_buffer buf = {0};
    int s = cli_output_open(&out, out_path, "--out", err);
    if (!s) s = cli_buffer_open(&buf, err);
    if (!s) {
        bkf_product_output po = bkf_product_output_default(buf.stream);
        po.format = format;
        po.program = CLI_PROGRAM " " CLI_VERSION;
        po.command = command;
        po.warn = warn_stderr;
        po.warn_data = argc > 0 ? argv[0] : (char *)"";
        s = write(spec, &po, err);
        int c = cli_buffer_close(&buf, s ? NULL : err);
        if (!s) s = c;
    }
    if (!s)
        s = cli_output_write(&out, buf.data, buf.size, err);
    else
        cli_output_abort(&out);
    cli_buffer_free(&buf);
    free(command);
    return s;
}
