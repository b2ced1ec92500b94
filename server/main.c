/* main.c -- iird's entry point: picks the subcommand and nothing else. */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "commands.h"

const char *iir_tri_cgal_version(void);

static void usage(FILE *f)
{
    fprintf(f, "usage: iird <command> [options]   (iird <command> --help for details)\n"
               "\n"
               "commands:\n"
               "  serve      serve the web client and live frames over WebSockets\n"
               "  render     render a still, or an animation script's frames (PNG, EXR, PFM; MP4)\n"
               "  bench      time methods over a moving light against path-traced references\n"
               "  raybench   measure the machine's raw Embree ray rate and the path tracer's\n"
               "  params     list the methods' parameters (options and params fields)\n"
               "\n"
               "  --version  print the version and the libraries built in\n");
}

int main(int argc, char **argv)
{
    if (argc < 2) return usage(stderr), IIRD_EXIT_USAGE;
    const char *cmd = argv[1];
    if (!strcmp(cmd, "--help") || !strcmp(cmd, "-h")) return usage(stdout), 0;
    if (!strcmp(cmd, "--version")) {
        printf("iird %s (CGAL %s)\n", IIR_VERSION, iir_tri_cgal_version());
        return 0;
    }
    if (!strcmp(cmd, "serve")) return iird_cmd_serve(argc - 1, argv + 1);
    if (!strcmp(cmd, "render")) return iird_cmd_render(argc - 1, argv + 1);
    if (!strcmp(cmd, "raybench")) return iird_cmd_raybench(argc - 1, argv + 1);
    if (!strcmp(cmd, "bench")) return iird_cmd_bench(argc - 1, argv + 1);
    if (!strcmp(cmd, "params")) return iird_cmd_params(argc - 1, argv + 1);
    fprintf(stderr, "iird: unknown command '%s'\n", cmd);
    usage(stderr);
    return IIRD_EXIT_USAGE;
}
