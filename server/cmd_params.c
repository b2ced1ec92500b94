/* cmd_params.c -- `iird params`: every method's parameters as the tables declare them, as help
 * text or as the Markdown of docs/cli.md's parameter section (a CLI test compares the two). */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "commands.h"

static void params_usage(FILE *f)
{
    fprintf(f, "usage: iird params [--method NAME] [--markdown]\n"
               "\n"
               "Prints the methods' parameters: name, values, default, range, what a change\n"
               "costs a running method. They are options of render, bench and serve, and fields\n"
               "of the live protocol's params message.\n"
               "\n"
               "  --method NAME   only this method's (pt, ir, iir)\n"
               "  --markdown      every table as Markdown (docs/cli.md, \"Method parameters\")\n");
}

int iird_cmd_params(int argc, char **argv)
{
    const char *method = NULL;
    bool markdown = false;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) return params_usage(stdout), 0;
        if (!strcmp(argv[i], "--markdown")) {
            markdown = true;
        } else if (!strcmp(argv[i], "--method") && i + 1 < argc) {
            method = argv[++i];
            if (!iir_method_tables(method)) {
                fprintf(stderr, "iird params: unknown method '%s'\n", method);
                return 2;
            }
        } else {
            params_usage(stderr);
            return IIRD_EXIT_USAGE;
        }
    }
    if (markdown)
        iird_print_params_markdown(stdout);
    else
        iird_print_params(stdout, method);
    return 0;
}
