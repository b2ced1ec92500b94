/* bench_refs.c -- the path-traced references of `iird bench` and their on-disk cache keyed by a
 * content hash (see bench.h). Not scoring (bench.c). */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bench.h"
#include "cli.h"
#include "iir/hash.h"
#include "iir/timer.h"

/* Bump when pt or the reference settings change what a cached file would hold. */
static const char CACHE_TAG[] = "iir-bench-ref-v4";

/* ---- hashing ---- */

/* Everything of the scene a reference image depends on: the triangles and their materials, the
 * vertices' shading normals, texture coordinates and tangents, the textures' texels. */
uint64_t iird_bench_scene_hash(const iir_scene *s)
{
    uint64_t h = IIR_HASH_BASIS;
    h = IIR_HASH(h, s->num_triangles);
    h = IIR_HASH(h, s->num_materials);
    for (uint32_t m = 0; m < s->num_materials; m++) h = iir_material_hash(h, &s->material_list[m]);
    for (uint32_t t = 0; t < s->num_triangles; t++) {
        for (int k = 0; k < 3; k++) h = IIR_HASH(h, s->positions[s->indices[3 * t + k]]);
        h = IIR_HASH(h, s->materials[t]);
    }
    size_t nv = s->num_vertices;
    bool has[3] = {s->vertex_normals != NULL, s->texcoords != NULL, s->tangents != NULL};
    h = IIR_HASH(h, has);
    if (s->vertex_normals) h = iir_hash_bytes(h, s->vertex_normals, nv * sizeof(iir_vec3));
    if (s->texcoords) h = iir_hash_bytes(h, s->texcoords, nv * sizeof(iir_vec2));
    if (s->tangents) h = iir_hash_bytes(h, s->tangents, nv * 4 * sizeof(float));
    for (uint32_t i = 0; i < s->num_textures; i++) h = iir_texture_hash(h, s->textures[i]);
    return h;
}

static uint64_t ref_key(const iird_bench *b, const iir_view *v, const iir_params *p)
{
    uint64_t h = iir_hash_bytes(IIR_HASH_BASIS, CACHE_TAG, sizeof CACHE_TAG);
    h = IIR_HASH(h, b->scene_hash);
    h = IIR_HASH(h, v->num_lights);
    for (uint32_t i = 0; i < v->num_lights; i++) h = iir_light_hash(h, &v->lights[i]);
    h = IIR_HASH(h, v->camera.position);
    h = IIR_HASH(h, v->camera.target);
    h = IIR_HASH(h, v->camera.up);
    h = IIR_HASH(h, v->camera.fov_y);
    int32_t size[2] = {b->o->width, b->o->height};
    h = IIR_HASH(h, size);
    const iir_param_table *const *t = iir_method_tables("pt"); /* every value pt renders with */
    for (int k = 0; t[k]; k++)
        for (int i = 0; i < t[k]->count; i++) {
            double v = iir_method_param_value(&t[k]->rows[i], p);
            h = IIR_HASH(h, v);
        }
    return h;
}

/* ---- the cache folder ---- */

/* --ref-cache DIR, else $XDG_CACHE_HOME/iir/refs, else out/refcache; "" turns the cache off. */
static void choose_cache_dir(iird_bench *b)
{
    const char *opt = b->o->ref_cache, *xdg = getenv("XDG_CACHE_HOME");
    if (opt)
        snprintf(b->cache_dir, sizeof b->cache_dir, "%s", opt);
    else if (xdg && *xdg)
        snprintf(b->cache_dir, sizeof b->cache_dir, "%s/iir/refs", xdg);
    else
        snprintf(b->cache_dir, sizeof b->cache_dir, "out/refcache");
    iir_error err = {0};
    const char *what = opt ? "--ref-cache" : "the default cache";
    if (b->cache_dir[0] && iird_prepare_dir(b->cache_dir, what, &err) != IIR_OK) {
        fprintf(stderr, "iird bench: warning: no reference cache: %s\n", err.msg);
        b->cache_dir[0] = '\0';
    }
}

/* The cached reference, or NULL (missing, unreadable or of another size). */
static iir_image *cache_get(const iird_bench *b, uint64_t key)
{
    char path[4200];
    iir_image *img = NULL;
    snprintf(path, sizeof path, "%s/%016llx.pfm", b->cache_dir, (unsigned long long)key);
    if (access(path, R_OK) != 0 || iir_image_read_pfm(path, &img, NULL) != IIR_OK) return NULL;
    if (img->width != b->o->width || img->height != b->o->height) {
        iir_image_destroy(img);
        return NULL;
    }
    return img;
}

/* Writes through a temporary file and a rename, so a concurrent or interrupted run never leaves
 * half a file under the key. */
static void cache_put(const iird_bench *b, uint64_t key, const iir_image *img)
{
    char path[4200], tmp[4300];
    iir_error err = {0};
    snprintf(path, sizeof path, "%s/%016llx.pfm", b->cache_dir, (unsigned long long)key);
    snprintf(tmp, sizeof tmp, "%s.%ld.tmp.pfm", path, (long)getpid());
    if (iir_image_write_pfm(img, tmp, &err) != IIR_OK || rename(tmp, path) != 0) {
        fprintf(stderr, "iird bench: warning: reference cache: cannot write %s\n", path);
        remove(tmp);
    }
}

/* ---- rendering ---- */

static iir_status save_image(const iird_bench *b, const iird_bench_refset *rs, int i,
                             iir_error *err)
{
    if (!b->o->save_images || !b->o->out_dir) return IIR_OK;
    char path[4200];
    if (rs->bounces == 2)
        snprintf(path, sizeof path, "%s/ref_%05d.pfm", b->o->out_dir, b->first + i);
    else
        snprintf(path, sizeof path, "%s/ref_b%d_%05d.pfm", b->o->out_dir, rs->bounces,
                 b->first + i);
    return iir_image_write(rs->img[i], path, 0.f, err);
}

/* Reference of run frame i into rs->img[i]: from the cache, else rendered with pt (created on
 * first need into *pt) and cached. */
static iir_status reference(iird_bench *b, iird_bench_refset *rs, const iir_params *p,
                            iir_method **pt, int i, iir_error *err)
{
    iir_view v = iird_bench_view(b, i);
    uint64_t key = ref_key(b, &v, p);
    if (b->cache_dir[0] && (rs->img[i] = cache_get(b, key))) return b->refs_cached++, IIR_OK;
    double t0 = iir_now_ms();
    iir_status st = *pt ? IIR_OK : iir_method_create("pt", b->scene, b->rt, p, pt, err);
    rs->img[i] = iir_image_create(b->o->width, b->o->height);
    if (!rs->img[i]) return iir_fail(err, IIR_ERR_NOMEM, "out of memory");
    iir_frame_stats fs;
    if (st == IIR_OK) st = iir_method_render(*pt, &v, rs->img[i], &fs, err);
    if (st == IIR_OK && b->cache_dir[0]) cache_put(b, key, rs->img[i]);
    b->refs_rendered++;
    b->refs_render_ms += iir_now_ms() - t0;
    return st;
}

/* Whether reference number j (in the order they are visited) is this run's. */
static bool in_share(const iird_bench *b, int j)
{
    return j >= b->share_first && j < b->share_end;
}

static iir_status refset_render(iird_bench *b, iird_bench_refset *rs, iird_progress *bar, int *done,
                                iir_error *err)
{
    iir_params p = b->o->params;
    iir_status st = iir_params_set(&p, iir_method_find_param("pt", "spp"), b->o->ref_spp, err);
    if (st == IIR_OK)
        st = iir_params_set(&p, iir_method_find_param("pt", "bounces"), rs->bounces, err);
    if (st == IIR_OK) st = iir_params_set(&p, iir_method_any_param("jitter"), b->o->ref_aa, err);
    iir_method *pt = NULL;
    for (int i = 0; st == IIR_OK && i < b->frames; i++) {
        if (!iird_bench_is_ref_frame(b, i) || !in_share(b, b->ref_job++)) continue;
        if (iird_interrupted()) st = iir_fail(err, IIR_ERR_INTERRUPTED, "interrupted");
        if (st == IIR_OK) st = reference(b, rs, &p, &pt, i, err);
        if (st == IIR_OK) st = save_image(b, rs, i, err);
        if (b->o->refs_only) iir_image_destroy(rs->img[i]), rs->img[i] = NULL; /* cached */
        ++*done;
        double rate = iird_progress_rate(bar, *done, iir_now_ms());
        iird_progress_set_after(bar, "bench", iird_bench_after_s(b, -1, rate * 1e3));
        iird_progress_update(bar, *done);
    }
    iir_method_destroy(pt);
    return st;
}

iir_status iird_bench_references(iird_bench *b, iir_error *err)
{
    if (b->o->ref_spp == 0) return IIR_OK;
    double t0 = iir_now_ms();
    choose_cache_dir(b);
    for (int i = 0; i < b->frames; i++) b->refs_total += iird_bench_is_ref_frame(b, i);
    b->refs_total *= b->num_refsets;
    b->share_first = 0, b->share_end = b->refs_total; /* all, or the I-th of N shares of them */
    if (b->o->segments)
        iird_segment_range(b->o->segment, b->o->segments, b->refs_total, &b->share_first,
                           &b->share_end);
    if (b->o->refs_only && !b->cache_dir[0])
        return iir_fail(err, IIR_ERR_INVALID,
                        "--refs-only renders into the reference cache, which is off: give "
                        "--ref-cache DIR (a shared folder on a farm)");
    int done = 0;
    iird_progress bar;
    iird_progress_start(&bar, "references", b->refs_total);
    iir_status st = IIR_OK;
    for (int s = 0; st == IIR_OK && s < b->num_refsets; s++)
        st = refset_render(b, &b->refsets[s], &bar, &done, err);
    iird_progress_finish(&bar);
    b->refs_s = (iir_now_ms() - t0) / 1e3;
    return st;
}
