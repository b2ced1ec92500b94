/* cmd_raybench.c -- `iird raybench`: the raw Embree ray rate on a scene beside the path tracer's
 * own ray rate on the same scene, measured in one run so the ratio is honest. */
#include <getopt.h>
#include <stdio.h>

#include "cli.h"
#include "commands.h"
#include "iir/method.h"
#include "iir/raybench.h"

typedef struct bench_opts {
    const char *scene, *scenes_dir;
    long rays;
    int width, height;
    iir_params params;
} bench_opts;

static void raybench_usage(FILE *f)
{
    fprintf(f, "usage: iird raybench [SCENE] [options]\n"
               "\n"
               "Traces random incoherent rays (origins on surfaces, uniform directions) through\n"
               "SCENE with no shading, then renders it with the path tracer, and prints both ray\n"
               "rates and their ratio. Without SCENE, the built-in Cornell box.\n"
               "\n"
               "  --rays N       raw rays per kind (default 4000000)\n"
               "  --size WxH     path tracer image (default 320x240)\n"
               "  --scenes DIR   where scene names are looked up\n"
               "  -h, --help     this text; pt's parameters follow (here spp defaults to 32)\n");
}

enum { OPT_RAYS = 1, OPT_SIZE, OPT_SCENES };

static iir_status parse_option(void *ctx, int c, const char *arg, iir_error *err)
{
    bench_opts *o = ctx;
    switch (c) {
    case OPT_RAYS:
        return iird_parse_int(arg, "--rays", 1, 1l << 28, &o->rays, err);
    case OPT_SIZE:
        return iird_parse_size(arg, 4096, &o->width, &o->height, err);
    case OPT_SCENES:
        o->scenes_dir = arg;
        return IIR_OK;
    }
    return iir_fail(err, IIR_ERR_INTERNAL, "unhandled option %d", c);
}

static const char *pt_only(const void *ctx)
{
    (void)ctx;
    return "pt";
}

static int parse_args(int argc, char **argv, bench_opts *o)
{
    static const struct option longopts[] = {{"rays", required_argument, 0, OPT_RAYS},
                                             {"size", required_argument, 0, OPT_SIZE},
                                             {"scenes", required_argument, 0, OPT_SCENES},
                                             {"help", no_argument, 0, 'h'},
                                             {0, 0, 0, 0}};
    static const iird_command cmd = {"raybench", longopts, raybench_usage, parse_option, pt_only};
    return iird_parse_command(&cmd, argc, argv, o, &o->params, &o->scene);
}

static iir_status run_pt(const bench_opts *o, const iir_scene *scene, const iir_rt *rt,
                         iir_frame_stats *fs, iir_error *err)
{
    iir_method *m = NULL;
    iir_image *img = iir_image_create(o->width, o->height);
    if (!img) return iir_fail(err, IIR_ERR_NOMEM, "out of memory for the image");
    iir_status st = iir_method_create("pt", scene, rt, &o->params, &m, err);
    iir_view view = {scene->lights, scene->num_lights, scene->camera};
    if (st == IIR_OK) st = iir_method_render(m, &view, img, fs, err);
    iir_method_destroy(m);
    iir_image_destroy(img);
    return st;
}

static void print_report(const iir_scene *scene, const iir_raybench_result *r,
                         const iir_frame_stats *fs)
{
    double pt_rays = (double)iir_raystats_total(&fs->rays);
    double pt_rate = pt_rays / (fs->total_ms * 1e-3);
    double occl = (double)fs->rays.n[IIR_RAYS_SHADOW];
    /* What raw Embree would take for the same mix of closest-hit and occlusion rays. */
    double raw_ms = (pt_rays - occl) / r->closest_per_s * 1e3 + occl / r->occluded_per_s * 1e3;
    printf("scene %s: %u triangles, %d threads\n", scene->name, scene->num_triangles, r->threads);
    printf("raw closest-hit : %8.2f Mrays/s  (%llu rays, %.0f%% hit)\n", r->closest_per_s / 1e6,
           (unsigned long long)r->rays, r->hit_fraction * 100);
    printf("raw occlusion   : %8.2f Mrays/s\n", r->occluded_per_s / 1e6);
    printf("pt (shading incl): %7.2f Mrays/s  (%.1f Mrays: %.0f%% closest-hit, %.0f%% shadow)\n",
           pt_rate / 1e6, pt_rays / 1e6, 100 * (pt_rays - occl) / pt_rays, 100 * occl / pt_rays);
    printf("pt / raw closest-hit rate      : %.0f%%\n", 100 * pt_rate / r->closest_per_s);
    printf("pt / raw rate for the same mix : %.0f%%\n", 100 * raw_ms / fs->total_ms);
}

int iird_cmd_raybench(int argc, char **argv)
{
    bench_opts o = {.rays = 4000000, .width = 320, .height = 240, .params = iir_params_default()};
    iir_error err = {0};
    if (iir_params_set(&o.params, iir_method_find_param("pt", "spp"), 32, &err) != IIR_OK)
        return iird_report("raybench", &err);
    int rc = parse_args(argc, argv, &o);
    if (rc >= 0) return rc;
    iir_scene *scene = NULL;
    iir_rt *rt = NULL;
    iir_raybench_result r = {0};
    iir_frame_stats fs = {0};
    iir_status st = iir_scene_open(o.scene, iird_scenes_dir(o.scenes_dir), &scene, &rt, &err);
    if (st == IIR_OK)
        st = iir_raybench_run(
            scene, rt, (uint64_t)o.rays,
            (uint64_t)iir_method_param_value(iir_method_any_param("seed"), &o.params), &r, &err);
    if (st == IIR_OK) st = run_pt(&o, scene, rt, &fs, &err);
    if (st == IIR_OK) print_report(scene, &r, &fs);
    rc = st == IIR_OK ? 0 : iird_report("raybench", &err);
    iir_rt_destroy(rt);
    iir_scene_destroy(scene);
    return rc;
}
