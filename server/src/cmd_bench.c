/* cmd_bench.c -- `iird bench`: frame-coherence experiments. Every method runs over the same light
 * path; pt references (one bounce, like iir) are rendered at every K-th frame and its successor,
 * and each method's frames there get RMSE, relative MSE and flicker (DESIGN section 10). Writes a
 * per-frame CSV and prints a summary with the ratios measured in this one run. */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench.h"
#include "cli.h"
#include "commands.h"
#include "iir/metrics.h"
#include "orbit.h"

static void bench_usage(FILE *f)
{
    fprintf(f,
            "usage: iird bench [SCENE] [options]\n"
            "\n"
            "Runs each method over a light path -- an animation script, or a smooth orbit of the\n"
            "scene's spot light -- and compares it with path-traced references: frame times per\n"
            "phase, rays, VPL churn, error and flicker.\n"
            "\n"
            "  --anim PATH          animation script (docs/animation-format.md) moving the spot\n"
            "                       and camera; frames from the script\n"
            "  --methods LIST       comma-separated methods (default iir,ir)\n"
            "  --frames N           frames on the orbit (default 200); with --anim, at most N\n"
            "  --size WxH           image size (default 512x384)\n"
            "  --ref-spp N          reference samples per pixel (default 256; 0 = no references)\n"
            "  --ref-every K        references at frames 0, 1, K, K+1, ... (default 50)\n"
            "  --ref-aa             antialiased references (default: through pixel centres, as\n"
            "                       the interactive methods shade)\n"
            "  --out DIR            write DIR/frames.csv (the directory must exist)\n"
            "  --save-images        also write DIR/ref_NNNNN.pfm and DIR/<method>_NNNNN.pfm at\n"
            "                       the reference frames\n"
            "  --scenes DIR         where scene names are looked up\n"
            "\n%s",
            IIRD_METHOD_HELP);
}

enum {
    OPT_METHODS = 1,
    OPT_FRAMES,
    OPT_SIZE,
    OPT_REF_SPP,
    OPT_REF_EVERY,
    OPT_OUT,
    OPT_SCENES,
    OPT_SAVE,
    OPT_REF_AA,
    OPT_ANIM
};

static iir_status parse_option(void *ctx, int c, const char *arg, iir_error *err)
{
    iird_bench_opts *o = ctx;
    long v = 0;
    iir_status st = IIR_OK;
    switch (c) {
    case OPT_METHODS:
        o->methods = arg;
        break;
    case OPT_OUT:
        o->out_dir = arg;
        break;
    case OPT_SCENES:
        o->scenes_dir = arg;
        break;
    case OPT_SAVE:
        o->save_images = true;
        break;
    case OPT_REF_AA:
        o->ref_aa = true;
        break;
    case OPT_ANIM:
        o->anim_path = arg;
        break;
    case OPT_SIZE:
        st = iird_parse_size(arg, 4096, &o->width, &o->height, err);
        break;
    case OPT_FRAMES:
        if ((st = iird_parse_int(arg, "--frames", 2, 100000, &v, err)) == IIR_OK)
            o->frames = (int)v, o->frames_given = true;
        break;
    case OPT_REF_SPP:
        if ((st = iird_parse_int(arg, "--ref-spp", 0, 1 << 20, &v, err)) == IIR_OK)
            o->ref_spp = (int)v;
        break;
    case OPT_REF_EVERY:
        if ((st = iird_parse_int(arg, "--ref-every", 2, 100000, &v, err)) == IIR_OK)
            o->ref_every = (int)v;
        break;
    }
    return st;
}

static int parse_args(int argc, char **argv, iird_bench_opts *o)
{
    static const struct option longopts[] = {{"methods", required_argument, 0, OPT_METHODS},
                                             {"frames", required_argument, 0, OPT_FRAMES},
                                             {"size", required_argument, 0, OPT_SIZE},
                                             {"ref-spp", required_argument, 0, OPT_REF_SPP},
                                             {"ref-every", required_argument, 0, OPT_REF_EVERY},
                                             {"out", required_argument, 0, OPT_OUT},
                                             {"scenes", required_argument, 0, OPT_SCENES},
                                             {"save-images", no_argument, 0, OPT_SAVE},
                                             {"ref-aa", no_argument, 0, OPT_REF_AA},
                                             {"anim", required_argument, 0, OPT_ANIM},
                                             {"help", no_argument, 0, 'h'},
                                             IIRD_METHOD_LONGOPTS,
                                             {0, 0, 0, 0}};
    static const iird_command cmd = {"bench", longopts, bench_usage, parse_option};
    return iird_parse_command(&cmd, argc, argv, o, &o->params, &o->scene);
}

int iird_cmd_bench(int argc, char **argv)
{
    iird_bench_opts o = {.methods = "iir,ir",
                         .frames = 200,
                         .width = 512,
                         .height = 384,
                         .ref_spp = 256,
                         .ref_every = 50,
                         .params = iir_params_default()};
    int rc = parse_args(argc, argv, &o);
    if (rc >= 0) return rc;
    iir_error err = {0};
    iird_bench run = {0};
    iird_catch_interrupts();
    iir_status st = iird_bench_setup(&run, &o, &err);
    if (st == IIR_OK) st = iird_bench_references(&run, &err);
    for (int m = 0; st == IIR_OK && m < run.num_methods; m++) st = iird_bench_method(&run, m, &err);
    if (st == IIR_OK) st = iird_bench_write_csv(&run, &err);
    if (st == IIR_OK) iird_bench_summary(&run, stdout);
    rc = st == IIR_OK ? 0 : iird_report("bench", &err);
    iird_bench_free(&run);
    return rc;
}
