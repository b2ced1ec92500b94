/* cmd_render.c -- `iird render`: one still of a scene with any method, written as PNG, EXR or
 * PFM. Long renders refine in chunks so the progress bar moves and Ctrl-C keeps what is done.
 * With --anim it parses the animation options and hands over to cmd_render_anim.c. */
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "iir/image.h"
#include "iir/method.h"
#include "render_anim.h"

typedef iird_render_opts render_opts;

static void render_usage(FILE *f)
{
    fprintf(
        f,
        "usage: iird render [SCENE] --out FILE.{png,exr,pfm} [options]\n"
        "       iird render [SCENE] --anim PATH --out DIR [--frames A:B | --segment I/N]\n"
        "                   [--format F] [--video FILE.mp4] [options]\n"
        "       iird render --merge DIR [--video FILE.mp4]\n"
        "\n"
        "Renders one still, or with --anim every frame of an animation script in order.\n"
        "SCENE is a name in the scenes directory, a scene folder or a file (.obj, .gltf, .glb,\n"
        ".scene.json); without it, the built-in Cornell box.\n"
        "\n"
        "  --out FILE|DIR       output image; the format follows the extension (required).\n"
        "                       With --anim a directory (created if missing) that gets\n"
        "                       frame_NNNNN.<format> and render.json\n"
        "  --method NAME        %s (default pt; with --anim iir)\n"
        "  --size WxH           image size (default 512x512; with --anim the script's size\n"
        "                       (a recording's: the browser's), else 512 high and as wide as\n"
        "                       the scene camera's aspect asks, 910x512 when it gives none)\n"
        "  --exposure E         PNG (and video) exposure in stops (default 0; with --anim\n"
        "                       the script's exposure when it has one)\n"
        "  --anim PATH          animation script (docs/animation-format.md), or a path the\n"
        "                       scene's sidecar names\n"
        "  --frames A:B         with --anim: script frames A..B-1 (B excluded); A: = to the end.\n"
        "                       Frames before A are re-rendered small, unwritten, to warm up\n"
        "  --segment I/N        with --anim: the I-th (from 0) of N contiguous shares of the\n"
        "                       frames, warmed up as --frames; its log is\n"
        "                       DIR/render.part-I-of-N.json (a farm's array task; resumes)\n"
        "  --merge DIR          check a directory's segments (every part there, the same\n"
        "                       settings, every frame once) and write DIR/render.json (and\n"
        "                       with --video the video)\n"
        "  --format F           with --anim: png | exr | pfm (default png)\n"
        "  --video FILE.mp4     with --anim: also an H.264 video of the frames (needs ffmpeg)\n"
        "  --scenes DIR         where scene names are looked up (default: with --anim the\n"
        "                       script's scenes folder (a recording's: the daemon's), else\n"
        "                       ./scenes)\n" IIRD_CACHE_MAX_HELP
        "  -h, --help           this text (with --method M: M's parameters only)\n"
        "\n"
        "Exit codes: 0 ok, 2 bad input, 3 file error, 4 unsupported, 64 usage, 130 interrupted.\n",
        iird_method_choices());
}

enum {
    OPT_OUT = 1,
    OPT_METHOD,
    OPT_SIZE,
    OPT_EXPOSURE,
    OPT_SCENES,
    OPT_ANIM,
    OPT_FRAMES,
    OPT_FORMAT,
    OPT_VIDEO,
    OPT_SEGMENT,
    OPT_MERGE,
    OPT_CACHE_MAX
};

static iir_status parse_option(void *ctx, int c, const char *arg, iir_error *err)
{
    render_opts *o = ctx;
    iir_status st = IIR_OK;
    switch (c) {
    case OPT_OUT:
        o->out = arg;
        break;
    case OPT_METHOD:
        o->method = arg;
        break;
    case OPT_SCENES:
        o->scenes_dir = arg;
        break;
    case OPT_CACHE_MAX:
        st = iird_set_cache_max(arg, err);
        break;
    case OPT_SIZE:
        st = iird_parse_size(arg, IIR_IMAGE_MAX_DIM, &o->width, &o->height, err);
        o->size_given = true;
        break;
    case OPT_ANIM:
        o->anim = arg;
        break;
    case OPT_VIDEO:
        o->video = arg;
        break;
    case OPT_FRAMES:
        o->frames_arg = arg;
        st = iird_parse_frame_range(arg, &o->first, &o->end, err);
        break;
    case OPT_SEGMENT:
        o->segment_arg = arg;
        st = iird_parse_segment(arg, &o->segment, &o->segments, err);
        break;
    case OPT_MERGE:
        o->merge = arg;
        break;
    case OPT_FORMAT:
        o->format_arg = arg;
        st = iird_parse_format(arg, &o->format, err);
        break;
    case OPT_EXPOSURE:
        st = iird_parse_float(arg, "--exposure", -30.f, 30.f, &o->exposure, err);
        o->exposure_given = true;
        break;
    }
    return st;
}

/* The method: --method, else pt for a still and iir for an animation. */
static const char *render_method(const void *ctx)
{
    const render_opts *o = ctx;
    return o->method ? o->method : o->anim ? "iir" : "pt";
}

/* --merge DIR takes only --video: -1 when that holds, else the usage exit code. */
static int check_merge(const render_opts *o)
{
    const char *other = o->out              ? "--out"
                        : o->anim           ? "--anim"
                        : o->frames_arg     ? "--frames"
                        : o->segment_arg    ? "--segment"
                        : o->format_arg     ? "--format"
                        : o->size_given     ? "--size"
                        : o->exposure_given ? "--exposure"
                        : o->scene          ? "SCENE"
                        : o->params.count   ? "method parameters"
                                            : NULL;
    if (!other) return -1;
    fprintf(stderr,
            "iird render: --merge DIR takes no %s (only --video): the parts' render.json "
            "files hold the settings\n",
            other);
    return IIRD_EXIT_USAGE;
}

/* Returns -1 when parsing succeeded, else the exit code. */
static int parse_args(int argc, char **argv, render_opts *o)
{
    static const struct option longopts[] = {{"out", required_argument, 0, OPT_OUT},
                                             {"method", required_argument, 0, OPT_METHOD},
                                             {"size", required_argument, 0, OPT_SIZE},
                                             {"exposure", required_argument, 0, OPT_EXPOSURE},
                                             {"scenes", required_argument, 0, OPT_SCENES},
                                             {"cache-max", required_argument, 0, OPT_CACHE_MAX},
                                             {"anim", required_argument, 0, OPT_ANIM},
                                             {"frames", required_argument, 0, OPT_FRAMES},
                                             {"format", required_argument, 0, OPT_FORMAT},
                                             {"video", required_argument, 0, OPT_VIDEO},
                                             {"segment", required_argument, 0, OPT_SEGMENT},
                                             {"merge", required_argument, 0, OPT_MERGE},
                                             {"help", no_argument, 0, 'h'},
                                             {0, 0, 0, 0}};
    static const iird_command cmd = {"render", longopts, render_usage, parse_option, render_method};
    int rc = iird_parse_command(&cmd, argc, argv, o, &o->params, &o->scene);
    if (rc >= 0) return rc;
    if (o->merge) return check_merge(o);
    if (!o->out) {
        fprintf(stderr, "iird render: --out %s is required (see iird render --help)\n",
                o->anim ? "DIR" : "FILE");
        return IIRD_EXIT_USAGE;
    }
    const char *anim_only = o->frames_arg    ? "--frames"
                            : o->segment_arg ? "--segment"
                            : o->format_arg  ? "--format"
                                             : "--video";
    if (!o->anim && (o->frames_arg || o->segment_arg || o->format_arg || o->video)) {
        fprintf(stderr, "iird render: %s needs --anim (see iird render --help)\n", anim_only);
        return IIRD_EXIT_USAGE;
    }
    if (o->segment_arg && (o->frames_arg || o->video)) {
        fprintf(stderr, "iird render: --segment %s: %s\n", o->segment_arg,
                o->frames_arg ? "give --frames or --segment, not both"
                              : "the video comes from the merge: iird render --merge DIR --video "
                                "FILE.mp4");
        return IIRD_EXIT_USAGE;
    }
    o->method = render_method(o);
    if (o->anim) return -1; /* its default size follows the scene (cmd_render_anim.c) */
    iir_error err = {0};
    if (iird_check_output(o->out, &err) != IIR_OK) return iird_report("render", &err);
    return -1;
}

/* Largest divisor of total that is at most total/20, so ~20 progress steps add up to exactly it. */
static int chunk_for(uint64_t total)
{
    uint64_t limit = total / 20 > 1 ? total / 20 : 1;
    for (uint64_t d = limit; d > 1; d--)
        if (total % d == 0) return (int)d;
    return 1;
}

/* A still is the method's converged frame (iir_method_converged_at: pt's refine_passes samples,
 * at least spp; ir's and iir's refine_passes passes) into *total (0: one frame, for a method that
 * cannot refine). A method with spp (pt) renders it in about 20 chunks of equal samples -- its
 * image depends on the total only -- so the progress bar moves and Ctrl-C keeps what is done; the
 * others refine one pass at a time. *chunked: the parameters to create the method with. */
static iir_status still_total(const render_opts *o, iir_params *chunked, uint64_t *total,
                              iir_error *err)
{
    *total = iir_method_converged_at(o->method, &o->params);
    const iir_param *spp = iir_method_find_param(o->method, "spp");
    *chunked = o->params;
    return spp && *total > 0 ? iir_params_set(chunked, spp, chunk_for(*total), err) : IIR_OK;
}

static iir_status render_still(iir_method *m, uint64_t total, const iir_scene *scene,
                               iir_image *img, iir_frame_stats *sum, iir_error *err)
{
    iir_view view = {scene->lights, scene->num_lights, scene->camera};
    iir_frame_stats fs;
    iird_progress bar;
    iird_progress_start(&bar, "render", (double)total);
    iir_status st = iir_method_render(m, &view, img, &fs, err);
    *sum = fs;
    while (st == IIR_OK && iir_method_can_refine(m) && fs.samples_per_pixel < total) {
        iird_progress_update(&bar, (double)fs.samples_per_pixel);
        if (iird_interrupted())
            return iir_fail(err, IIR_ERR_INTERRUPTED, "interrupted after %llu of %llu %s",
                            (unsigned long long)fs.samples_per_pixel, (unsigned long long)total,
                            iir_method_find_param(iir_method_name(m), "spp") ? "samples per pixel"
                                                                             : "refinement passes");
        st = iir_method_refine(m, img, &fs, err);
        sum->total_ms += fs.total_ms;
        iir_raystats_add(&sum->rays, &fs.rays);
        sum->samples_per_pixel = fs.samples_per_pixel;
    }
    iird_progress_finish(&bar);
    return st;
}

/* What the frame holds: samples per pixel (pt), the ray trees' cut branches (whitted, hybrid),
 * radiosity's refinement passes, the VPLs of a method that does not refine (rsm, hier), or
 * refinement passes and the VPLs. */
static void work_text(const render_opts *o, const iir_frame_stats *fs, char *buf, size_t n)
{
    unsigned long long done = (unsigned long long)fs->samples_per_pixel;
    const char *s = done == 1 ? "" : "s";
    if (iir_method_find_param(o->method, "spp"))
        snprintf(buf, n, "%llu sample%s per pixel", done, s);
    else if (iir_method_find_param(o->method, "min_weight")) /* whitted, hybrid */
        snprintf(buf, n, "a ray tree per pixel");
    else if (iir_method_find_param(o->method, "patch_area")) /* radiosity */
        snprintf(buf, n, "a radiosity solution, %llu refinement pass%s", done,
                 done == 1 ? "" : "es");
    else if (!iir_method_converged_at(o->method, &o->params)) /* rsm, hier: no refinement */
        snprintf(buf, n, "one frame (%s does not refine) over %u VPLs", o->method, fs->vpl.count);
    else if (fs->vpl.descendants > 0) /* iir with bounces > 2 */
        snprintf(buf, n, "%llu refinement pass%s over %u VPLs (+%u of later bounces)", done,
                 done == 1 ? "" : "es", fs->vpl.count, fs->vpl.descendants);
    else
        snprintf(buf, n, "%llu refinement pass%s over %u VPLs", done, done == 1 ? "" : "es",
                 fs->vpl.count);
}

/* The method's own counters as ", name value" each (a share as a percentage); "" for none. */
static void counters_text(const char *method, const iir_frame_stats *fs, char *buf, size_t n)
{
    const iir_counter *c;
    int k = iir_method_counters(method, &c);
    size_t used = 0;
    buf[0] = '\0';
    for (int i = 0; i < k && used < n; i++)
        used +=
            (size_t)(c[i].kind == IIR_COUNTER_SHARE
                         ? snprintf(buf + used, n - used, ", %s %.2f%%", c[i].name,
                                    100 * fs->counter[i])
                         : snprintf(buf + used, n - used, ", %s %.0f", c[i].name, fs->counter[i]));
}

static void print_summary(const render_opts *o, const iir_scene *scene, const iir_frame_stats *fs)
{
    double rays = (double)iir_raystats_total(&fs->rays);
    char work[96], counters[256], settings[1024];
    work_text(o, fs, work, sizeof work);
    counters_text(o->method, fs, counters, sizeof counters);
    iird_settings_text(o->method, &o->params, settings, sizeof settings);
    printf("wrote %s: %s, %dx%d, method %s, %s%s, %.2f s, %.1f Mrays (%.2f Mrays/s)\n"
           "%s settings: %s\n",
           o->out, scene->name, o->width, o->height, o->method, work, counters, fs->total_ms / 1e3,
           rays / 1e6, fs->total_ms > 0 ? rays / (fs->total_ms * 1e3) : 0.0, o->method, settings);
}

/* The camera note and the warnings before rendering: what the method leaves out. */
static void before_render(const render_opts *o, const iir_scene *scene)
{
    iird_note_camera("render", scene);
    iird_warn_dropped("render", o->method, &o->params, scene, scene->lights, scene->num_lights);
}

int iird_cmd_render(int argc, char **argv)
{
    render_opts o = {.width = 512,
                     .height = 512,
                     .end = -1,
                     .argc = argc,
                     .argv = argv,
                     .params = iir_params_default()};
    int rc = parse_args(argc, argv, &o);
    if (rc >= 0) return rc;
    if (o.merge) return iird_render_merge(&o);
    if (o.anim) return iird_render_anim(&o);

    iir_error err = {0};
    iir_scene *scene = NULL;
    iir_rt *rt = NULL;
    iir_method *m = NULL;
    iir_image *img = iir_image_create(o.width, o.height);
    iir_params chunked;
    uint64_t total = 0;
    iir_status st = iir_method_params_validate(o.method, &o.params, NULL, NULL, &err);
    if (st == IIR_OK) st = still_total(&o, &chunked, &total, &err);
    if (st == IIR_OK) st = iird_check_memory(o.method, &o.params, o.width, o.height, &err);
    if (st == IIR_OK)
        st = iir_scene_open(o.scene, iird_scenes_dir(o.scenes_dir), &scene, &rt, &err);
    if (st == IIR_OK) before_render(&o, scene);
    if (st == IIR_OK) st = iir_method_create(o.method, scene, rt, &chunked, &m, &err);
    iir_frame_stats fs = {0};
    iird_catch_interrupts();
    if (st == IIR_OK) st = render_still(m, total, scene, img, &fs, &err);
    if (st == IIR_OK || (st == IIR_ERR_INTERRUPTED && fs.samples_per_pixel > 0)) {
        iir_error werr = {0};
        if (iir_image_write(img, o.out, o.exposure, &werr) != IIR_OK)
            st = werr.status, err = werr;
        else if (st == IIR_OK)
            print_summary(&o, scene, &fs);
        else
            fprintf(stderr, "iird render: wrote the partial image to %s\n", o.out);
    }
    if (st == IIR_OK && iird_image_black(img)) {
        iir_view view = {scene->lights, scene->num_lights, scene->camera};
        iird_warn_black("render", "the image is", scene, rt, &view);
    }
    rc = st == IIR_OK ? 0 : iird_report("render", &err);
    iir_method_destroy(m);
    iir_image_destroy(img);
    iir_rt_destroy(rt);
    iir_scene_destroy(scene);
    return rc;
}
