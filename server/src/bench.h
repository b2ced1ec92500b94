/* bench.h -- the state of one `iird bench` run and its steps: set-up, references, one method over
 * the path, CSV, summary. Single-threaded from the caller's side. */
#ifndef IIRD_BENCH_H
#define IIRD_BENCH_H

#include <stdbool.h>
#include <stdio.h>

#include "iir/anim.h"
#include "iir/image.h"
#include "iir/method.h"
#include "iir/rt.h"
#include "iir/scene.h"

enum { IIRD_BENCH_MAX_METHODS = 8 };

typedef struct iird_bench_opts {
    const char *scene, *scenes_dir, *methods, *out_dir;
    const char *anim_path; /* animation script driving light and camera; NULL = built-in orbit */
    int frames, width, height, ref_spp, ref_every;
    bool frames_given; /* --frames was given: with a script, at most that many frames */
    bool save_images;  /* write reference-frame images (PFM) into out_dir */
    bool ref_aa;       /* box-filtered references instead of pixel-centred ones */
    iir_params params;
} iird_bench_opts;

typedef struct iird_bench_row {
    iir_frame_stats stats;
    double rmse, relmse, flicker; /* NAN where no reference exists */
} iird_bench_row;

typedef struct iird_bench {
    const iird_bench_opts *o;
    iir_scene *scene;
    iir_rt *rt;
    uint32_t spot;  /* index of the scene light that moves */
    iir_anim *anim; /* NULL: the built-in orbit */
    int frames;     /* frames in this run */
    iir_light *lights;
    char names[IIRD_BENCH_MAX_METHODS][16];
    int num_methods;
    iir_image **refs;     /* per frame, NULL where no reference */
    iird_bench_row *rows; /* num_methods x frames */
} iird_bench;

iir_status iird_bench_setup(iird_bench *b, const iird_bench_opts *o, iir_error *err);
iir_status iird_bench_references(iird_bench *b, iir_error *err);
iir_status iird_bench_method(iird_bench *b, int m, iir_error *err);
iir_status iird_bench_write_csv(const iird_bench *b, iir_error *err);
void iird_bench_summary(const iird_bench *b, FILE *f);
void iird_bench_free(iird_bench *b);

#endif
