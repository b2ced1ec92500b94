/* bench.h -- the state of one `iird bench` run and its steps: set-up (methods x settings), the
 * path-traced references and their on-disk cache, one method and setting over the path, and the
 * outputs (frames.csv, summary.json, the printed summary, the charts). Single-threaded from the
 * caller's side. Option parsing is cmd_bench.c's. */
#ifndef IIRD_BENCH_H
#define IIRD_BENCH_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "iir/anim.h"
#include "iir/image.h"
#include "iir/method.h"
#include "iir/rt.h"
#include "iir/scene.h"

enum {
    IIRD_BENCH_MAX_METHODS = 8,
    IIRD_BENCH_MAX_RUNS = 64,   /* methods x settings */
    IIRD_BENCH_MAX_SWEEPS = 4,  /* --sweep flags; their values form a cartesian product */
    IIRD_BENCH_MAX_VALUES = 16, /* values of one --sweep */
    IIRD_BENCH_MAX_REFSETS = 4, /* distinct reference bounce counts */
};

/* One --sweep NAME=V1,V2,...: NAME is a method parameter (its option without "--"). */
typedef struct iird_bench_sweep {
    char name[24]; /* the option's spelling: "sm-res" */
    const iir_param *row;
    int num_values;
    char values[IIRD_BENCH_MAX_VALUES][24];
} iird_bench_sweep;

typedef struct iird_bench_opts {
    const char *scene, *scenes_dir, *methods, *out_dir;
    const char *anim;      /* --anim: a script file or a path the scene names; NULL = orbit */
    const char *ref_cache; /* reference cache folder; NULL = the default, "" = off */
    int first, frames;     /* --frames A:B: first = A, frames = B (or N, the count, with A = 0) */
    int width, height, ref_spp, ref_every;
    bool range_given;  /* --frames A:B (with a script, B must not pass its end) */
    bool frames_given; /* --frames N or A:B */
    bool save_images;  /* write reference-frame images (PFM) into out_dir */
    bool ref_aa;       /* box-filtered references (and pt runs) instead of pixel-centred */
    bool no_charts;    /* do not call tools/plot_bench.py */
    bool refs_only; /* --refs-only: render this share of the references into the cache, no runs */
    const char *segment_arg; /* --segment I/N as given (with --refs-only), or NULL */
    int segment, segments;   /* the share: references [I T / N, (I + 1) T / N) of the T needed */
    int num_sweeps;
    iird_bench_sweep sweeps[IIRD_BENCH_MAX_SWEEPS];
    iir_params params;
    int argc; /* the command line, for summary.json */
    char **argv;
} iird_bench_opts;

/* One method with one setting. */
typedef struct iird_bench_run {
    char method[16];
    char setting[96]; /* "default", or "vpls=256" / "vpls=256;kmax=16" */
    iir_params params;
    int refset; /* index into iird_bench.refsets: the references with this run's bounce count */
} iird_bench_run;

typedef struct iird_bench_row {
    iir_frame_stats stats;
    double rmse, relmse, flicker; /* NAN where no reference exists */
    double rss_mb;                /* resident set after the frame */
    double method_mb;             /* the method's VPLs and shadow maps (0 without VPLs) */
    double mean_lum;              /* mean luminance of the frame: ~0 for a black frame */
} iird_bench_row;

/* References of one bounce count, per frame of the run (NULL where none). */
typedef struct iird_bench_refset {
    int bounces;
    iir_image **img;
} iird_bench_refset;

typedef struct iird_bench {
    const iird_bench_opts *o;
    iir_scene *scene;
    iir_rt *rt;
    uint64_t scene_hash; /* FNV-1a 64 of the triangles and their materials */
    uint32_t spot;       /* index of the light the light track (or the built-in orbit) moves */
    iir_anim *anim;      /* NULL: the built-in orbit */
    char path_label[4096];
    int first, frames; /* run frames first .. first + frames - 1 of the path */
    int path_frames;   /* frames of the whole path */
    iir_light *lights;
    int num_runs;
    iird_bench_run runs[IIRD_BENCH_MAX_RUNS];
    int num_refsets;
    iird_bench_refset refsets[IIRD_BENCH_MAX_REFSETS];
    int refs_total, refs_cached; /* references needed, and how many came from the cache */
    int refs_rendered;           /* references rendered (not read from the cache) ... */
    double refs_render_ms;       /* ... and the time they took */
    char cache_dir[4096];        /* "" = no cache */
    iird_bench_row *rows;        /* num_runs x frames */
    double refs_s;               /* seconds spent on references (cache reads included) */
    int ref_job;                 /* references visited so far, in order (the shares' index) */
    int share_first, share_end;  /* the references of this run: all, or --segment's share */
    double wall_s;               /* whole run, for summary.json */
} iird_bench;

/* ---- bench.c: set-up and running ---- */

/* Loads the scene and path, expands methods x sweeps into runs. IIR_ERR_INVALID naming the option
 * (--methods, --sweep, --frames) for bad requests, or naming the script's field for light tracks
 * the scene's lights do not fit (iir_anim_check_lights). */
iir_status iird_bench_setup(iird_bench *b, const iird_bench_opts *o, iir_error *err);
/* Runs run r over every frame, scoring frames that have references. */
iir_status iird_bench_run_one(iird_bench *b, int r, iir_error *err);
/* Seconds the runs after phase `current` (-1: the references; else a run) will take, for the
 * progress bar's whole-bench ETA: each run's frames times its expected ms per frame -- measured
 * by a finished run of the same method, else for pt scaled from the references rendered, else
 * current_ms (the current phase's measured ms per frame). < 0 when current_ms is unknown (< 0). */
double iird_bench_after_s(const iird_bench *b, int current, double current_ms);
/* The lights and camera of run frame i (0-based within the range): every light the script
 * animates moved, the others as the scene has them; lights live in b->lights. */
iir_view iird_bench_view(iird_bench *b, int i);
/* Reference frames: the first two of the range, and every K-th after with its successor. */
bool iird_bench_is_ref_frame(const iird_bench *b, int i);
/* After the runs: a warning per run with entirely black frames, saying why the first may be. */
void iird_bench_warn_black(iird_bench *b);
void iird_bench_free(iird_bench *b);

/* ---- bench_refs.c: references and their cache ---- */

/* Renders, or reads from the cache, every reference set's frames: pt with the set's bounce count
 * at --ref-spp, seeded by --seed. A cached reference is DIR/<key>.pfm, key = FNV-1a 64 of a
 * version tag, the scene hash, the frame's lights and camera, the size, spp, bounces, seed and
 * jitter. A cache that cannot be written only costs a warning. */
iir_status iird_bench_references(iird_bench *b, iir_error *err);
/* FNV-1a 64 of the scene's content: every triangle's positions and its material. */
uint64_t iird_bench_scene_hash(const iir_scene *s);

/* ---- bench_out.c: outputs ---- */

iir_status iird_bench_write_csv(const iird_bench *b, iir_error *err);
iir_status iird_bench_write_json(const iird_bench *b, iir_error *err);
void iird_bench_summary(const iird_bench *b, FILE *f);
/* Calls tools/plot_bench.py on out_dir when python3 with matplotlib is there; otherwise says how.
 * Returns false when the script failed. */
bool iird_bench_charts(const iird_bench *b, FILE *f);

#endif
