/* cmd_bench.c -- `iird bench`'s command line: frame-coherence experiments (DESIGN section 10).
 * Every method runs over the same light path, once per setting of the --sweep values it uses; pt
 * references with the method's bounce count are rendered (or read from their cache) at every K-th
 * frame and its successor, and each run's frames there get RMSE, relative MSE and flicker. Writes
 * frames.csv, summary.json and charts, and prints a summary with the ratios of this one run.
 * The work itself is bench*.c's. */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench.h"
#include "cli.h"
#include "iir/timer.h"
#include "commands.h"

static void bench_usage(FILE *f)
{
    fprintf(f,
            "usage: iird bench [SCENE] [options]\n"
            "\n"
            "Runs each method over a light path -- an animation script, or a smooth orbit of the\n"
            "scene's spot light -- and compares it with path-traced references: frame times per\n"
            "phase, rays, VPL churn, memory, error and flicker.\n"
            "\n"
            "  --anim PATH|NAME     animation script (docs/animation-format.md), or the name of a\n"
            "                       path the scene's sidecar lists (e.g. orbit, teleport)\n"
            "  --methods LIST       comma-separated methods (default iir,ir)\n"
            "  --sweep NAME=V1,...  run every method that has parameter NAME once per value\n"
            "                       (e.g. vpls=64,256,1024 or spp=1,4,16); several --sweep flags\n"
            "                       multiply; the CSV's setting column says which\n"
            "  --frames N | A:B     N frames from 0, or the half-open range A:B of the path\n"
            "                       (orbit: default 200; script: all of its frames)\n"
            "  --size WxH           image size (default 512x384)\n"
            "  --ref-spp N          reference samples per pixel (default 256; 0 = no references)\n"
            "  --ref-every K        references at range frames 0, 1, K, K+1, ... (default 50)\n"
            "  --ref-aa             antialiased references and pt runs (default: through pixel\n"
            "                       centres, as the interactive methods shade)\n"
            "  --ref-cache DIR      reference cache (default $XDG_CACHE_HOME/iir/refs, else\n"
            "                       out/refcache); --no-ref-cache to always render\n"
            "  --out DIR            write DIR/frames.csv, DIR/summary.json and charts (the\n"
            "                       directory is created if missing)\n"
            "  --no-charts          do not run tools/plot_bench.py\n"
            "  --refs-only          only render the references into the cache (no runs,\n"
            "                       no --out): a farm's work before one bench finds them\n"
            "  --segment I/N        with --refs-only: the I-th (from 0) of N shares of them\n"
            "  --save-images        also write DIR/ref_NNNNN.pfm and DIR/<method>[_<setting>]_\n"
            "                       NNNNN.pfm at the reference frames\n"
            "  --scenes DIR         where scene names are looked up (default: the --anim\n"
            "                       script's scenes folder, else ./scenes)\n" IIRD_CACHE_MAX_HELP
            "  -h, --help           this text (with --methods: their parameters only)\n");
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
    OPT_ANIM,
    OPT_SWEEP,
    OPT_REF_CACHE,
    OPT_NO_REF_CACHE,
    OPT_NO_CHARTS,
    OPT_REFS_ONLY,
    OPT_SEGMENT,
    OPT_CACHE_MAX
};

/* --frames N (= 0:N) or A:B, half-open, at least two frames. */
static iir_status parse_frames(iird_bench_opts *o, const char *arg, iir_error *err)
{
    char *end = NULL;
    long a = 0, b = strtol(arg, &end, 10);
    if (end != arg && *end == ':') {
        const char *rest = end + 1;
        a = b, b = strtol(rest, &end, 10);
        if (end == rest || *end || a < 0 || b > 1000000)
            return iir_fail(err, IIR_ERR_INVALID,
                            "--frames '%s' is not N or A:B (0 <= A < B <= 1000000)", arg);
        if (b - a < 2)
            return iir_fail(err, IIR_ERR_INVALID, "--frames %ld:%ld: bench needs at least 2 frames",
                            a, b);
        o->range_given = true;
    } else {
        iir_status st = iird_parse_int(arg, "--frames", 2, 1000000, &b, err);
        if (st != IIR_OK) return st;
    }
    o->first = (int)a, o->frames = (int)b, o->frames_given = true;
    return IIR_OK;
}

/* Checks each value as the parameter's option would, on a scratch set. */
static iir_status add_sweep_values(iird_bench_sweep *s, const char *list, iir_error *err)
{
    char buf[1024];
    snprintf(buf, sizeof buf, "%s", list);
    for (char *save = NULL, *tok = strtok_r(buf, ",", &save); tok;
         tok = strtok_r(NULL, ",", &save)) {
        if (s->num_values == IIRD_BENCH_MAX_VALUES || strlen(tok) >= sizeof s->values[0])
            return iir_fail(err, IIR_ERR_INVALID, "--sweep %s: at most %d values of %zu characters",
                            s->name, IIRD_BENCH_MAX_VALUES, sizeof s->values[0] - 1);
        iir_params scratch = iir_params_default();
        iir_error verr = {0};
        iir_status st = iird_parse_param(s->name, tok, &scratch, &verr);
        if (st != IIR_OK) return iir_fail(err, st, "--sweep %s: %s", s->name, verr.msg);
        snprintf(s->values[s->num_values++], sizeof s->values[0], "%s", tok);
    }
    if (s->num_values == 0) return iir_fail(err, IIR_ERR_INVALID, "--sweep %s: no values", s->name);
    return IIR_OK;
}

static iir_status parse_sweep(iird_bench_opts *o, const char *arg, iir_error *err)
{
    const char *eq = strchr(arg, '=');
    size_t len = eq ? (size_t)(eq - arg) : 0;
    if (!eq || len == 0 || len >= sizeof o->sweeps[0].name)
        return iir_fail(err, IIR_ERR_INVALID,
                        "--sweep '%s' is not NAME=V1,V2,... (e.g. vpls=64,256,1024)", arg);
    if (o->num_sweeps == IIRD_BENCH_MAX_SWEEPS)
        return iir_fail(err, IIR_ERR_INVALID, "--sweep: at most %d of them", IIRD_BENCH_MAX_SWEEPS);
    iird_bench_sweep *s = &o->sweeps[o->num_sweeps];
    memset(s, 0, sizeof *s);
    char key[sizeof s->name];
    snprintf(key, sizeof key, "%.*s", (int)len, arg);
    if (!(s->row = iird_param_by_option(key)))
        return iir_fail(err, IIR_ERR_INVALID,
                        "--sweep %.*s: not a parameter of any method (iird bench --help lists "
                        "them)",
                        (int)len, arg);
    iir_param_option_name(s->row, s->name, sizeof s->name);
    for (int i = 0; i < o->num_sweeps; i++)
        if (!strcmp(o->sweeps[i].name, s->name))
            return iir_fail(err, IIR_ERR_INVALID, "--sweep %s: given twice", s->name);
    iir_status st = add_sweep_values(s, eq + 1, err);
    if (st == IIR_OK) o->num_sweeps++;
    return st;
}

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
    case OPT_CACHE_MAX:
        return iird_set_cache_max(arg, err);
    case OPT_SAVE:
        o->save_images = true;
        break;
    case OPT_REF_AA:
        o->ref_aa = true;
        break;
    case OPT_ANIM:
        o->anim = arg;
        break;
    case OPT_REF_CACHE:
        o->ref_cache = arg;
        break;
    case OPT_NO_REF_CACHE:
        o->ref_cache = "";
        break;
    case OPT_NO_CHARTS:
        o->no_charts = true;
        break;
    case OPT_REFS_ONLY:
        o->refs_only = true;
        break;
    case OPT_SEGMENT:
        o->segment_arg = arg;
        st = iird_parse_segment(arg, &o->segment, &o->segments, err);
        break;
    case OPT_SWEEP:
        st = parse_sweep(o, arg, err);
        break;
    case OPT_SIZE:
        st = iird_parse_size(arg, 4096, &o->width, &o->height, err);
        break;
    case OPT_FRAMES:
        st = parse_frames(o, arg, err);
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

static const char *bench_methods(const void *ctx)
{
    return ((const iird_bench_opts *)ctx)->methods;
}

/* Every --sweep names a parameter of one of the methods at least. */
static iir_status check_sweeps(const iird_bench_opts *o, iir_error *err)
{
    for (int i = 0; i < o->num_sweeps; i++) {
        iir_params one = iir_params_default();
        iir_status st = iir_params_set(&one, o->sweeps[i].row, o->sweeps[i].row->def, err);
        if (st == IIR_OK) st = iird_check_params_for(o->methods, &one, err);
        if (st != IIR_OK) {
            char msg[sizeof err->msg];
            snprintf(msg, sizeof msg, "%s", err->msg);
            return iir_fail(err, st, "--sweep %s", msg + 2); /* "--sm-res is not ..." */
        }
    }
    return IIR_OK;
}

static int parse_args(int argc, char **argv, iird_bench_opts *o)
{
    static const struct option longopts[] = {{"methods", required_argument, 0, OPT_METHODS},
                                             {"frames", required_argument, 0, OPT_FRAMES},
                                             {"size", required_argument, 0, OPT_SIZE},
                                             {"ref-spp", required_argument, 0, OPT_REF_SPP},
                                             {"ref-every", required_argument, 0, OPT_REF_EVERY},
                                             {"ref-cache", required_argument, 0, OPT_REF_CACHE},
                                             {"no-ref-cache", no_argument, 0, OPT_NO_REF_CACHE},
                                             {"out", required_argument, 0, OPT_OUT},
                                             {"no-charts", no_argument, 0, OPT_NO_CHARTS},
                                             {"scenes", required_argument, 0, OPT_SCENES},
                                             {"cache-max", required_argument, 0, OPT_CACHE_MAX},
                                             {"save-images", no_argument, 0, OPT_SAVE},
                                             {"ref-aa", no_argument, 0, OPT_REF_AA},
                                             {"anim", required_argument, 0, OPT_ANIM},
                                             {"sweep", required_argument, 0, OPT_SWEEP},
                                             {"refs-only", no_argument, 0, OPT_REFS_ONLY},
                                             {"segment", required_argument, 0, OPT_SEGMENT},
                                             {"help", no_argument, 0, 'h'},
                                             {0, 0, 0, 0}};
    static const iird_command cmd = {"bench", longopts, bench_usage, parse_option, bench_methods};
    o->argc = argc, o->argv = argv;
    int rc = iird_parse_command(&cmd, argc, argv, o, &o->params, &o->scene);
    if (rc >= 0) return rc;
    const char *bad = o->segment_arg && !o->refs_only ? "--segment needs --refs-only"
                      : o->refs_only && o->out_dir
                          ? "--refs-only writes only the reference cache: no --out"
                      : o->refs_only && o->ref_spp == 0 ? "--refs-only needs --ref-spp above 0"
                                                        : NULL;
    if (bad) fprintf(stderr, "iird bench: %s (see iird bench --help)\n", bad);
    return bad ? IIRD_EXIT_USAGE : -1;
}

/* --refs-only: what this share did. */
static void print_refs_only(const iird_bench *b)
{
    const iird_bench_opts *o = b->o;
    int mine = b->share_end - b->share_first;
    printf("references%s%s: %d of the %d needed; %d rendered, %d already in %s (%.1f s)\n",
           o->segments ? " share " : "", o->segments ? o->segment_arg : "", mine, b->refs_total,
           b->refs_rendered, b->refs_cached, b->cache_dir, b->refs_s);
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
    double t0 = iir_now_ms();
    iird_catch_interrupts();
    iir_status st = check_sweeps(&o, &err);
    if (st == IIR_OK) st = iird_bench_setup(&run, &o, &err);
    if (st == IIR_OK && o.out_dir) st = iird_prepare_dir(o.out_dir, "--out", &err);
    if (st == IIR_OK) st = iird_bench_references(&run, &err);
    if (o.refs_only) {
        if (st == IIR_OK) print_refs_only(&run);
        rc = st == IIR_OK ? 0 : iird_report("bench", &err);
        iird_bench_free(&run);
        return rc;
    }
    for (int r = 0; st == IIR_OK && r < run.num_runs; r++) st = iird_bench_run_one(&run, r, &err);
    if (st == IIR_OK) iird_bench_warn_black(&run);
    run.wall_s = (iir_now_ms() - t0) / 1e3;
    if (st == IIR_OK) st = iird_bench_write_csv(&run, &err);
    if (st == IIR_OK) st = iird_bench_write_json(&run, &err);
    if (st == IIR_OK) iird_bench_summary(&run, stdout);
    if (st == IIR_OK) iird_bench_charts(&run, stdout);
    rc = st == IIR_OK ? 0 : iird_report("bench", &err);
    iird_bench_free(&run);
    return rc;
}
