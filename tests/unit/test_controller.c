/* test_controller.c -- the frame-time controller (controller.h). Its rule against a plant whose
 * frame times are a cost model with noise from a fixed seed (deterministic: no wall clock decides
 * an outcome): converging to reachable targets within 15% over 100 frames, never alternating two
 * settings frame to frame and never undoing a cut that bought time, about the cheapest rung for an
 * unreachable target, the top for a generous one, following a new target and a costlier motion;
 * never below its floor (ctl_vpls_min, ctl_sm_res_min); on a busy machine (frames as long whatever
 * the setting) undoing its cuts, holding the quality and saying "busy". Then iir with target_fps on
 * the Cornell box, with targets so far from any machine's frame time that the outcome does not
 * depend on the machine: only frames of a moved light feed the controller (none: no figure), the
 * set follows the controller's N, maps of a new resolution are for new VPLs only, the stats carry
 * the controller's state, target_fps is a live change, and target_fps 0 brings the asked N and maps
 * back in the next frame. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "iir/controller.h"
#include "iir/method.h"
#include "iir/rng.h"
#include "testutil.h"

/* ---- the plant ---- */

/* A renderer's frame time as the controller's model has it, with different unit costs than any
 * real one and multiplicative noise: what a frame at setting s costs. */
typedef struct plant {
    double rest_ms, eval_ns, texel_ns, tap_ms, step_us, pixels, maps, noise;
    double busy_ms; /* > 0: a busy machine, every frame takes this long whatever its setting */
    iir_rng rng;
} plant;

static plant plant_make(uint64_t seed)
{
    plant p = {.rest_ms = 2.0,
               .eval_ns = 4.0,
               .texel_ns = 20.0,
               .tap_ms = 0.05,
               .step_us = 6.0,
               .pixels = 120000.0,
               .maps = 8.0,
               .noise = 0.10};
    p.rng = iir_rng_make(seed, 7);
    return p;
}

static iir_ctl_sample plant_frame(plant *p, iir_ctl_setting s)
{
    double n2 = (double)s.interleave * s.interleave, res2 = (double)s.sm_res * s.sm_res;
    double evals = p->pixels * s.vpls / n2;
    double jitter = 1.0 + p->noise * (2.0 * iir_rng_uniform(&p->rng) - 1.0);
    iir_ctl_sample m = {.setting = s,
                        .step_ms = p->step_us * 1e-3 * s.vpls * jitter,
                        .shadowmap_ms = p->texel_ns * 1e-6 * p->maps * res2 * jitter,
                        .indirect_ms = p->eval_ns * 1e-6 * evals * jitter,
                        .filter_ms = p->tap_ms * n2 * jitter,
                        .vpls = s.vpls,
                        .vpl_evals = evals,
                        .maps = p->maps};
    m.total_ms = p->rest_ms * jitter + m.step_ms + m.shadowmap_ms + m.indirect_ms + m.filter_ms;
    if (p->busy_ms > 0.0) { /* other work shares the cores: every phase stretched alike */
        double k = p->busy_ms * jitter / m.total_ms;
        m.step_ms *= k, m.shadowmap_ms *= k, m.indirect_ms *= k, m.filter_ms *= k;
        m.total_ms = p->busy_ms * jitter;
    }
    return m;
}

enum { FRAMES = 300, TAIL = 100 };

typedef struct run {
    iir_ctl_setting set[FRAMES];
    double ms[FRAMES];
    int alternations; /* frames t with set[t] == set[t - 2] != set[t - 1] */
} run;

static bool same(iir_ctl_setting a, iir_ctl_setting b)
{
    return a.vpls == b.vpls && a.interleave == b.interleave && a.sm_res == b.sm_res;
}

static void drive(iir_ctl *c, plant *p, run *r, int from, int to)
{
    for (int t = from; t < to; t++) {
        r->set[t] = iir_ctl_current(c);
        iir_ctl_sample m = plant_frame(p, r->set[t]);
        r->ms[t] = m.total_ms;
        iir_ctl_update(c, &m);
        if (t >= 2 && same(r->set[t], r->set[t - 2]) && !same(r->set[t], r->set[t - 1]))
            r->alternations++;
    }
}

static double mean_ms(const run *r, int from, int to)
{
    double s = 0.0;
    for (int t = from; t < to; t++) s += r->ms[t];
    return s / (to - from);
}

static int moves(const run *r, int from, int to)
{
    int n = 0;
    for (int t = from + 1; t < to; t++) n += !same(r->set[t], r->set[t - 1]);
    return n;
}

/* A controller with its floor at 16 VPLs and maps of 32^2 (a quarter of 128^2): room to move. */
static iir_ctl *make_floor(double target_ms, int vpls_max, int start, int vpls_min, int sm_res_min)
{
    iir_ctl_config cfg = {.target_ms = target_ms,
                          .vpls_max = vpls_max,
                          .vpls_min = vpls_min,
                          .interleave = 4,
                          .sm_res = 128,
                          .sm_res_min = sm_res_min};
    iir_ctl *c = NULL;
    iir_error err = {0};
    if (iir_ctl_create(&cfg, start, &c, &err) != IIR_OK) fail_msg("%s", err.msg);
    return c;
}

static iir_ctl *make(double target_ms, int vpls_max, int start)
{
    return make_floor(target_ms, vpls_max, start, 16, 8);
}

/* Reachable targets from above and below the start: the last 100 frames' mean within 15% of the
 * target, settled (few moves), never alternating. */
static void test_converges(void **state)
{
    (void)state;
    static const double targets[] = {8.0, 12.0, 20.0, 35.0};
    static const int starts[] = {16, 256, 1024};
    for (size_t i = 0; i < sizeof targets / sizeof targets[0]; i++)
        for (size_t j = 0; j < sizeof starts / sizeof starts[0]; j++) {
            iir_ctl *c = make(targets[i], 1024, starts[j]);
            plant p = plant_make(1 + i * 3 + j);
            static run r;
            memset(&r, 0, sizeof r);
            drive(c, &p, &r, 0, FRAMES);
            double m = mean_ms(&r, FRAMES - TAIL, FRAMES);
            iir_ctl_setting s = iir_ctl_current(c);
            print_message("target %.0f ms from N %d: mean %.2f ms, N %d n %d res %d, %d moves "
                          "(%d in the last %d)\n",
                          targets[i], starts[j], m, s.vpls, s.interleave, s.sm_res,
                          moves(&r, 0, FRAMES), moves(&r, FRAMES - TAIL, FRAMES), TAIL);
            assert_true(fabs(m - targets[i]) <= 0.15 * targets[i]);
            assert_int_equal(r.alternations, 0);
            assert_true(moves(&r, FRAMES - TAIL, FRAMES) <= 4);
            iir_ctl_report rep;
            iir_ctl_get_report(c, &rep);
            assert_true(rep.reachable);
            assert_false(rep.busy);
            assert_int_equal(rep.undone, 0); /* every cut bought what it promised */
            assert_int_equal(rep.frames, FRAMES);
            assert_true(fabs(rep.mean_ms - targets[i]) <= 0.25 * targets[i]);
            iir_ctl_destroy(c);
        }
}

/* 30% noise: still settles and never alternates. */
static void test_noise_does_not_oscillate(void **state)
{
    (void)state;
    iir_ctl *c = make(15.0, 1024, 256);
    plant p = plant_make(99);
    p.noise = 0.30;
    static run r;
    memset(&r, 0, sizeof r);
    drive(c, &p, &r, 0, FRAMES);
    print_message("30%% noise: %d moves, %d in the last %d, mean %.2f ms\n", moves(&r, 0, FRAMES),
                  moves(&r, FRAMES - TAIL, FRAMES), TAIL, mean_ms(&r, FRAMES - TAIL, FRAMES));
    assert_int_equal(r.alternations, 0);
    assert_true(moves(&r, FRAMES - TAIL, FRAMES) <= 4);
    assert_true(fabs(mean_ms(&r, FRAMES - TAIL, FRAMES) - 15.0) <= 0.15 * 15.0);
    iir_ctl_destroy(c);
}

/* Below the cheapest rung: within 5% of the cheapest's time (near N_min, maps at a quarter) and
 * "not reachable"; far above the dearest: the top (N_max, the narrowest interleave). */
static void test_bounds(void **state)
{
    (void)state;
    static run r;
    iir_ctl *c = make(1.0, 1024, 256);
    plant p = plant_make(3);
    memset(&r, 0, sizeof r);
    drive(c, &p, &r, 0, FRAMES);
    iir_ctl_report rep;
    iir_ctl_get_report(c, &rep);
    print_message("1 ms: N %d n %d res %d, predicted %.2f ms\n", rep.setting.vpls,
                  rep.setting.interleave, rep.setting.sm_res, rep.predicted_ms);
    assert_false(rep.reachable);
    assert_false(rep.busy); /* its cuts bought time */
    assert_true(rep.setting.vpls < 32);
    assert_int_equal(rep.setting.sm_res, 32); /* maps would take most of it */
    for (int i = 0; i < rep.rungs; i++) {     /* about the cheapest rung */
        iir_ctl_setting s = iir_ctl_rung(c, i);
        assert_true(1.05 * iir_ctl_predict(c, &s) >= iir_ctl_predict(c, &rep.setting));
        assert_int_not_equal(s.interleave, 5); /* no rung wider than the floor's interleave */
    }
    iir_ctl_destroy(c);

    c = make(1000.0, 512, 64);
    memset(&r, 0, sizeof r);
    drive(c, &p, &r, 0, FRAMES);
    iir_ctl_get_report(c, &rep);
    assert_int_equal(rep.rung, rep.rungs - 1);
    assert_int_equal(rep.setting.vpls, 512); /* never past N_max */
    assert_int_equal(rep.setting.interleave, 2);
    assert_int_equal(r.alternations, 0);
    iir_ctl_destroy(c);
}

/* The floor (ctl_vpls_min 64, ctl_sm_res_min 64 of 128): an unreachable target never takes a
 * frame below it (the old controller went to 16 VPLs and 32^2 maps); the report names the floor.
 * A floor above ctl_vpls_max is ctl_vpls_max. */
static void test_floor(void **state)
{
    (void)state;
    static run r;
    memset(&r, 0, sizeof r);
    iir_ctl *c = make_floor(1.0, 1024, 256, 64, 64);
    plant p = plant_make(11);
    drive(c, &p, &r, 0, FRAMES);
    int below = 0;
    for (int t = 0; t < FRAMES; t++) below += r.set[t].vpls < 64 || r.set[t].sm_res < 64;
    iir_ctl_report rep;
    iir_ctl_get_report(c, &rep);
    print_message("floor 64 / 64^2 at 1 ms: N %d n %d res %d, %d frames below the floor\n",
                  rep.setting.vpls, rep.setting.interleave, rep.setting.sm_res, below);
    assert_int_equal(below, 0);
    assert_false(rep.reachable);
    assert_int_equal(rep.floor.vpls, 64);
    assert_int_equal(rep.floor.interleave, 4);
    assert_int_equal(rep.floor.sm_res, 64);
    assert_int_equal(rep.setting.sm_res, 64);
    assert_true(rep.setting.vpls <= 128);
    for (int i = 0; i < rep.rungs; i++) assert_true(iir_ctl_rung(c, i).vpls >= 64);
    iir_ctl_destroy(c);

    c = make_floor(20.0, 48, 32, 64, 64); /* floor over the ceiling: the ceiling */
    iir_ctl_get_report(c, &rep);
    assert_int_equal(rep.floor.vpls, 48);
    assert_int_equal(rep.rungs, 3); /* N 48 at interleave 4, 3, 2 */
    iir_ctl_destroy(c);
}

/* A busy machine: every frame takes 80 ms whatever the setting (the phases stretched alike, so the
 * model sees what it always sees and promises that fewer VPLs save time). Target 20 ms. The cut
 * is judged, buys nothing, is undone, and cuts wait 60, 120, 240 frames: most frames keep the
 * starting N 256, the report says busy, and no figure is wrong. Then the machine is free again
 * (the plain plant, 10 ms target: a cut is needed and buys its time): after the hold the
 * controller cuts, and this time keeps the cut. */
static void test_busy(void **state)
{
    (void)state;
    static run r;
    memset(&r, 0, sizeof r);
    iir_ctl *c = make(20.0, 1024, 256);
    plant p = plant_make(21);
    p.busy_ms = 80.0;
    drive(c, &p, &r, 0, FRAMES);
    int cut = 0;
    for (int t = 0; t < FRAMES; t++) cut += r.set[t].vpls < 256;
    iir_ctl_report rep;
    iir_ctl_get_report(c, &rep);
    print_message("busy 80 ms at 20 ms: %d of %d frames below N 256, %u cuts undone, N %d, "
                  "busy %d, mean %.1f ms\n",
                  cut, FRAMES, rep.undone, rep.setting.vpls, rep.busy, rep.mean_ms);
    assert_true(cut <= FRAMES / 10);
    assert_true(rep.undone >= 2);
    assert_true(rep.busy);
    assert_int_equal(rep.setting.vpls, 256);
    assert_int_equal(r.alternations, 0);

    static run q;
    memset(&q, 0, sizeof q);
    p.busy_ms = 0.0;
    iir_ctl_config cfg = {.target_ms = 10.0,
                          .vpls_max = 1024,
                          .vpls_min = 16,
                          .interleave = 4,
                          .sm_res = 128,
                          .sm_res_min = 8};
    iir_error err = {0};
    assert_int_equal(iir_ctl_configure(c, &cfg, &err), IIR_OK); /* a new target: no hold */
    drive(c, &p, &q, 0, 200);
    iir_ctl_get_report(c, &rep);
    print_message("free again at 10 ms: N %d, mean of the last 100 %.2f ms, undone %u, busy %d\n",
                  rep.setting.vpls, mean_ms(&q, 100, 200), rep.undone, rep.busy);
    assert_true(rep.setting.vpls < 256);
    assert_true(fabs(mean_ms(&q, 100, 200) - 10.0) <= 1.5);
    assert_false(rep.busy);
    iir_ctl_destroy(c);
}

/* A new target mid-run (fewer VPLs), then a costlier motion (five times the maps a frame: a fast
 * light; coarser maps): the controller follows each within 50 frames. */
static void test_follows_changes(void **state)
{
    (void)state;
    static run r;
    memset(&r, 0, sizeof r);
    iir_ctl *c = make(20.0, 1024, 256);
    plant p = plant_make(5);
    drive(c, &p, &r, 0, 100);
    iir_ctl_config cfg = {.target_ms = 10.0,
                          .vpls_max = 1024,
                          .vpls_min = 16,
                          .interleave = 4,
                          .sm_res = 128,
                          .sm_res_min = 8};
    iir_error err = {0};
    assert_int_equal(iir_ctl_configure(c, &cfg, &err), IIR_OK);
    drive(c, &p, &r, 100, 200);
    double m10 = mean_ms(&r, 150, 200);
    p.maps = 40.0;
    drive(c, &p, &r, 200, FRAMES);
    double m_fast = mean_ms(&r, 250, FRAMES);
    print_message("20 ms: N %d; 10 ms: N %d, mean %.2f; 5x maps: N %d res %d, mean %.2f\n",
                  r.set[99].vpls, r.set[199].vpls, m10, r.set[FRAMES - 1].vpls,
                  r.set[FRAMES - 1].sm_res, m_fast);
    assert_true(fabs(m10 - 10.0) <= 1.5);
    assert_true(fabs(m_fast - 10.0) <= 1.5);
    assert_true(r.set[199].vpls < r.set[99].vpls);
    assert_true(r.set[FRAMES - 1].sm_res < r.set[199].sm_res); /* coarser maps pay for them */
    assert_int_equal(r.alternations, 0);
    iir_ctl_report rep;
    iir_ctl_get_report(c, &rep);
    assert_int_equal(rep.undone, 0);
    iir_ctl_destroy(c);
}

static void test_bad_config(void **state)
{
    (void)state;
    iir_ctl_config cfg = {.target_ms = NAN,
                          .vpls_max = 256,
                          .vpls_min = 64,
                          .interleave = 4,
                          .sm_res = 128,
                          .sm_res_min = 64};
    iir_ctl *c = NULL;
    iir_error err = {0};
    assert_int_equal(iir_ctl_create(&cfg, 256, &c, &err), IIR_ERR_INVALID);
    assert_null(c);
    cfg.target_ms = 10.0, cfg.interleave = 9;
    assert_int_equal(iir_ctl_create(&cfg, 256, &c, &err), IIR_ERR_INVALID);
    assert_non_null(strstr(err.msg, "interleave"));
    cfg.interleave = 4, cfg.sm_res_min = 4;
    assert_int_equal(iir_ctl_create(&cfg, 256, &c, &err), IIR_ERR_INVALID);
    assert_non_null(strstr(err.msg, "sm_res_min"));
    cfg.sm_res_min = 64;
    assert_int_equal(iir_ctl_create(&cfg, 256, &c, &err), IIR_OK);
    iir_ctl_report rep; /* before any frame: no figure */
    iir_ctl_get_report(c, &rep);
    assert_true(rep.mean_ms == 0.0 && rep.predicted_ms == 0.0);
    assert_int_equal(rep.frames, 0);
    assert_true(rep.reachable);
    iir_ctl_destroy(c);
}

/* ---- iir with target_fps ---- */

typedef iir_test_cornell fixture;

/* `count` frames of the scene's view; with `move` the first light swings by 1 mm between two
 * positions, so every frame is an interactive one (a moved light) and few VPLs die. */
static iir_frame_stats frames(iir_method *m, const fixture *f, int w, int h, int count, bool move)
{
    iir_image *img = iir_image_create(w, h);
    iir_light lights[8];
    uint32_t nl = f->scene->num_lights < 8 ? f->scene->num_lights : 8;
    memcpy(lights, f->scene->lights, nl * sizeof *lights);
    iir_view v = {lights, nl, f->scene->camera};
    iir_frame_stats fs = {0};
    for (int i = 0; i < count; i++) {
        if (move) lights[0].position.x = f->scene->lights[0].position.x + (i % 2 ? 1e-3f : 0.f);
        iir_test_render(m, &v, img, &fs);
    }
    iir_image_destroy(img);
    return fs;
}

/* Maps of the set's non-null VPLs at resolution res, and at another one. */
static void count_maps(iir_method *m, int res, uint32_t *at, uint32_t *other)
{
    uint32_t n = 0;
    const iir_vpl *v = iir_method_vpls(m, &n);
    *at = *other = 0;
    for (uint32_t i = 0; i < n; i++)
        if (!v[i].null_sample) v[i].smap.res == res ? (*at)++ : (*other)++;
}

static void set_live(iir_method *m, const iir_params *p)
{
    bool restarted = true;
    iir_error err = {0};
    assert_int_equal(iir_method_set_params(m, p, &restarted, &err), IIR_OK);
    assert_false(restarted); /* the controller's parameters are live */
}

/* 1000 fps at 320x240 is out of reach of any machine (a frame's direct light and G-buffer alone
 * take longer): about the floor (ctl_vpls_min 64: N within 5% of its time) -- unless the machine
 * is so busy that the cut bought no measurable time, which the controller then says (busy) -- and
 * the set shrinks to its N keeping its 128^2 maps; 0.5 fps at 32x24 is beyond every rung: the set
 * grows to ctl_vpls_max, its new VPLs with maps of the main resolution. */
static void test_iir_follows(void **state)
{
    const fixture *f = *state;
    iir_params p = iir_params_default();
    iir_test_set(&p, "target_fps", 1000);
    iir_test_set(&p, "kmax", 64);
    iir_test_set(&p, "kmin", 0); /* no churn: the survivors stay */
    iir_method *m = iir_test_method(f, "iir", &p);
    iir_frame_stats fs = frames(m, f, 320, 240, 30, true);
    uint32_t old = 0, other = 0;
    count_maps(m, 128, &old, &other);
    print_message("1000 fps: N %u, %u of its maps kept at 128^2, mean %.2f ms over %llu frames, "
                  "busy %d (%u cuts undone)\n",
                  fs.vpl.count, old, fs.ctl.mean_ms, (unsigned long long)fs.ctl.frames, fs.ctl.busy,
                  fs.ctl.undone);
    assert_true(fs.controlled);
    assert_false(fs.ctl.reachable);
    assert_int_equal(fs.ctl.floor.vpls, 64);
    assert_true(fs.ctl.setting.vpls >= 64);
    assert_true(fs.ctl.setting.vpls <= 128 || fs.ctl.undone > 0);
    assert_true(fs.vpl.count >= 0.9 * fs.ctl.setting.vpls &&
                fs.vpl.count <= (uint32_t)fs.ctl.setting.vpls);
    assert_true(old > 0);                /* the survivors kept their maps */
    assert_int_equal(fs.ctl.frames, 29); /* the first frame is no interactive one */

    iir_params q = p;
    iir_test_set(&q, "target_fps", 0.5);
    iir_test_set(&q, "ctl_vpls_max", 128);
    set_live(m, &q);
    fs = frames(m, f, 32, 24, 60, true);
    print_message("0.5 fps: N %d n %d res %d, set %u, mean %.2f ms\n", fs.ctl.setting.vpls,
                  fs.ctl.setting.interleave, fs.ctl.setting.sm_res, fs.vpl.count, fs.ctl.mean_ms);
    assert_true(fs.ctl.reachable);
    assert_int_equal(fs.ctl.setting.vpls, 128);
    assert_int_equal(fs.vpl.count, 128);
    iir_method_destroy(m);
}

/* Frames of an unchanged view (a method's first, re-renders, what a refining session shows) are
 * no interactive frames: the controller gets none, has no figure (mean 0, frames 0) and keeps its
 * start (vpls 256) however far out of reach its target (the old controller took them, cut to its
 * bottom and reported their rate). Then frames of a moving light feed it, and it cuts. */
static void test_iir_interactive_only(void **state)
{
    const fixture *f = *state;
    iir_params p = iir_params_default();
    iir_test_set(&p, "target_fps", 1000);
    iir_method *m = iir_test_method(f, "iir", &p);
    iir_frame_stats fs = frames(m, f, 320, 240, 12, false);
    assert_true(fs.controlled);
    assert_int_equal(fs.ctl.frames, 0);
    assert_true(fs.ctl.mean_ms == 0.0);
    assert_int_equal(fs.ctl.moves, 0);
    assert_int_equal(fs.ctl.setting.vpls, 256);
    assert_int_equal(fs.vpl.count, 256);
    fs = frames(m, f, 320, 240, 12, true);
    print_message("12 still frames, then 12 moving: %llu measured, mean %.2f ms, N %d, %u moves\n",
                  (unsigned long long)fs.ctl.frames, fs.ctl.mean_ms, fs.ctl.setting.vpls,
                  fs.ctl.moves);
    assert_int_equal(fs.ctl.frames, 11); /* the first of them repeats the still view */
    assert_true(fs.ctl.mean_ms > 0.0);
    assert_true(fs.ctl.moves > 0); /* a cut (kept, or being judged against the clock) */
    iir_method_destroy(m);
}

/* target_fps 0 brings back the asked settings in the very next frame, of the same view: the set
 * at vpls (256), every map at sm_res (128^2) again; before, the controller held the set at its
 * ceiling ctl_vpls_max 64, with maps of 64^2 for its new VPLs while maps took too long (the old
 * method grew the set by kmax a frame, and only while frames came). */
static void test_iir_restores(void **state)
{
    const fixture *f = *state;
    iir_params p = iir_params_default();
    iir_test_set(&p, "target_fps", 1000);
    iir_test_set(&p, "ctl_vpls_max", 64);
    iir_method *m = iir_test_method(f, "iir", &p);
    iir_frame_stats fs = frames(m, f, 320, 240, 30, true);
    uint32_t at = 0, other = 0;
    count_maps(m, 128, &at, &other);
    print_message("1000 fps: set %u, maps %u at 128^2, %u coarser\n", fs.vpl.count, at, other);
    assert_true(fs.vpl.count <= 64);

    iir_test_set(&p, "target_fps", 0);
    set_live(m, &p);
    fs = frames(m, f, 320, 240, 1, false);
    count_maps(m, 128, &at, &other);
    print_message("target_fps 0, one frame: set %u, maps %u at 128^2, %u other\n", fs.vpl.count, at,
                  other);
    assert_false(fs.controlled);
    assert_int_equal(fs.vpl.count, 256);
    assert_int_equal(other, 0);
    assert_true(at > 200);
    iir_method_destroy(m);
}

int main(void)
{
    const struct CMUnitTest plant_tests[] = {
        cmocka_unit_test(test_converges),  cmocka_unit_test(test_noise_does_not_oscillate),
        cmocka_unit_test(test_bounds),     cmocka_unit_test(test_floor),
        cmocka_unit_test(test_busy),       cmocka_unit_test(test_follows_changes),
        cmocka_unit_test(test_bad_config),
    };
    const struct CMUnitTest iir_tests[] = {
        cmocka_unit_test(test_iir_follows),
        cmocka_unit_test(test_iir_interactive_only),
        cmocka_unit_test(test_iir_restores),
    };
    int failed = cmocka_run_group_tests(plant_tests, NULL, NULL);
    return failed +
           cmocka_run_group_tests(iir_tests, iir_test_cornell_setup, iir_test_cornell_teardown);
}
