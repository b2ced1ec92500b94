/* scene_notes.c -- what render, render --anim and bench tell the user about the scene on stderr:
 * the camera a scene without one was framed with, the lights and materials a method does not
 * render, and why an image came out entirely black. The facts come from core (iir_scene_describe_
 * camera, iir_method_dropped, iir_scene_explain_dark); this file only words and prints them. */
#include <stdlib.h>
#include <string.h>

#include "cli.h"

enum { MAX_DROPPED = 256 };

void iird_note_camera(const char *cmd, const iir_scene *scene)
{
    if (scene->camera_origin != IIR_CAMERA_OUTSIDE && scene->camera_origin != IIR_CAMERA_INSIDE)
        return;
    char text[400];
    iir_scene_describe_camera(scene, text, sizeof text);
    fprintf(stderr, "iird %s: camera: %s\n", cmd, text);
}

/* Whether out[0..i) already holds an entry with d's kind, name and text (the scene's notes come
 * with every method asked). */
static bool seen(const iir_dropped *out, uint32_t i, const iir_dropped *d)
{
    for (uint32_t k = 0; k < i; k++)
        if (!strcmp(out[k].kind, d->kind) && !strcmp(out[k].name, d->name) &&
            !strcmp(out[k].what, d->what))
            return true;
    return false;
}

static bool same_note(const iir_dropped *a, const iir_dropped *b)
{
    return !strcmp(a->method, b->method) && !strcmp(a->kind, b->kind) &&
           !strcmp(a->what, b->what) && a->note == b->note;
}

/* One line for all[i] and every later entry with the same method, kind and text (a scene with
 * fifty textured materials gets one line naming them), which are marked done: "warning:" for
 * what is left out, "note:" for what was made of the scene (iir_dropped.note). */
static void print_group(const char *cmd, iir_dropped *all, uint32_t n, uint32_t i, bool *done)
{
    enum { NAMES = 8 };
    char names[NAMES * 72] = "";
    size_t used = 0;
    uint32_t count = 0;
    for (uint32_t k = i; k < n; k++) {
        if (done[k] || !same_note(&all[i], &all[k])) continue;
        done[k] = true;
        if (count++ < NAMES)
            used += (size_t)snprintf(names + used, sizeof names - used, "%s'%s'",
                                     count > 1 ? ", " : "", all[k].name);
    }
    char more[48] = "";
    if (count > NAMES) snprintf(more, sizeof more, " and %u more", count - NAMES);
    fprintf(stderr, "iird %s: %s: %s%s%s%s %s%s: %s\n", cmd, all[i].note ? "note" : "warning",
            all[i].method, all[i].method[0] ? ": " : "", all[i].kind, count > 1 ? "s" : "", names,
            more, all[i].what);
}

/* Adds the k entries of got not in all[0..*n) to all (at most MAX_DROPPED; the rest to *lost). */
static void add_new(iir_dropped *all, uint32_t *n, uint32_t *lost, const iir_dropped *got,
                    uint32_t k)
{
    for (uint32_t i = 0; i < k && i < MAX_DROPPED; i++) {
        if (seen(all, *n, &got[i])) continue;
        if (*n < MAX_DROPPED)
            all[(*n)++] = got[i];
        else
            (*lost)++;
    }
    if (k > MAX_DROPPED) *lost += k - MAX_DROPPED;
}

void iird_warn_dropped(const char *cmd, const char *methods, const iir_params *params,
                       const iir_scene *scene, const iir_light *lights, uint32_t num_lights)
{
    iir_dropped *all = calloc(MAX_DROPPED, sizeof *all), *got = calloc(MAX_DROPPED, sizeof *got);
    bool *done = calloc(MAX_DROPPED, sizeof *done);
    uint32_t n = 0, lost = 0;
    char list[256], *save = NULL;
    snprintf(list, sizeof list, "%s", methods);
    for (char *m = strtok_r(list, ",", &save); all && got && done && m;
         m = strtok_r(NULL, ",", &save)) {
        add_new(all, &n, &lost, got,
                iir_method_dropped(m, scene, lights, num_lights, got, MAX_DROPPED));
        add_new(all, &n, &lost, got,
                iir_method_dropped_by_params(m, scene, params, got, MAX_DROPPED));
    }
    for (uint32_t i = 0; i < n; i++)
        if (!done[i]) print_group(cmd, all, n, i, done);
    if (lost) fprintf(stderr, "iird %s: warning: and %u more not rendered\n", cmd, lost);
    free(all);
    free(got);
    free(done);
}

void iird_log_scene_notes(const char *who, const iir_scene *scene)
{
    uint32_t n = scene->num_dropped;
    iir_dropped *all = n ? calloc(n, sizeof *all) : NULL;
    bool *done = n ? calloc(n, sizeof *done) : NULL;
    if (all && done) {
        memcpy(all, scene->dropped, n * sizeof *all);
        for (uint32_t i = 0; i < n; i++)
            if (!done[i]) print_group(who, all, n, i, done);
    }
    free(all);
    free(done);
}

bool iird_image_black(const iir_image *img)
{
    size_t n = (size_t)img->width * (size_t)img->height;
    for (size_t i = 0; i < n; i++)
        if (iir_max_comp(img->pixels[i]) > 0.f) return false;
    return true;
}

void iird_warn_black(const char *cmd, const char *what, const iir_scene *scene, const iir_rt *rt,
                     const iir_view *view)
{
    char why[400];
    iir_scene_explain_dark(scene, rt, view->lights, view->num_lights, &view->camera, why,
                           sizeof why);
    fprintf(stderr, "iird %s: warning: %s entirely black: %s\n", cmd, what, why);
}
