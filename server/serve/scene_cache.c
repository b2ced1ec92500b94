/* scene_cache.c -- scenes loaded once, shared read-only and reference-counted between sessions;
 * the list of scene names clients may ask for. Not sessions. */
#include "scene_cache.h"

#include "budget.h"

#include <assert.h>
#include <dirent.h>
#include <limits.h>
#include <pthread.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "cli.h"
#include "iir/timer.h"

typedef struct cache_slot {
    iird_scene_entry entry; /* first: a slot's address is its entry's */
    char key[PATH_MAX];     /* canonical path, or "builtin" */
    iir_scene *scene;
    iir_rt *rt;
    int refs;
    bool loading, pinned;
    uint64_t held; /* bytes reserved in the budget for it */
    struct cache_slot *next;
} cache_slot;

struct iird_scene_cache {
    char *dir;
    char dir_real[PATH_MAX]; /* dir's canonical path ("" when it does not exist) */
    bool follow_links;       /* names may resolve outside dir (--scenes-follow-links) */
    char **names; /* NULL-terminated; guarded by lock. Only the service thread adds names (a saved
                     scene), so it may read them without the lock. */
    pthread_mutex_t lock;
    pthread_cond_t loaded;     /* broadcast when a load finishes (either way) */
    cache_slot *slots;         /* guarded by lock */
    const cache_slot *startup; /* pinned before any session exists; its name may come from a path
                                  outside dir */
    iird_budget *budget;       /* where loaded scenes are counted; NULL: nowhere */
};

static int cmp_names(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static bool is_scene_file(const char *name)
{
    const char *dot = strrchr(name, '.');
    return dot && (!strcasecmp(dot, ".obj") || !strcasecmp(dot, ".gltf") ||
                   !strcasecmp(dot, ".glb") || strstr(name, ".scene.json"));
}

/* ======================== staying inside the scenes directory ======================== */

/* Whether path resolves (symbolic links followed) outside the scenes directory. A path that does
 * not resolve stays: loading it fails on its own. */
static bool path_leaves(const iird_scene_cache *c, const char *path)
{
    char real[PATH_MAX];
    if (!c->dir_real[0] || !realpath(path, real)) return false;
    size_t n = strlen(c->dir_real);
    if (n == 1) return false; /* the scenes directory is / */
    return strncmp(real, c->dir_real, n) != 0 || (real[n] != '/' && real[n] != '\0');
}

/* Whether scene `name` of the scenes directory, or a file directly in its folder (what the loader
 * picks), resolves outside the directory; never with --scenes-follow-links. */
static bool scene_leaves(const iird_scene_cache *c, const char *name)
{
    char path[PATH_MAX];
    if (c->follow_links) return false;
    snprintf(path, sizeof path, "%s/%s", c->dir, name);
    if (path_leaves(c, path)) return true;
    DIR *d = opendir(path);
    bool leaves = false;
    for (struct dirent *de; d && !leaves && (de = readdir(d));) {
        char inner[PATH_MAX];
        if (de->d_name[0] == '.') continue;
        int n = snprintf(inner, sizeof inner, "%s/%s", path, de->d_name);
        leaves = n > 0 && n < (int)sizeof inner && path_leaves(c, inner);
    }
    if (d) closedir(d);
    return leaves;
}

/* ======================== the list of names ======================== */

/* Folders and scene files directly in c's dir, as bare names; none that leaves the directory. */
static bool list_dir(const iird_scene_cache *c, char ***names, size_t *n)
{
    const char *dir = c->dir;
    DIR *d = opendir(dir);
    if (!d) return true; /* no scenes folder: only the built-in box */
    size_t cap = *n + 1;
    for (struct dirent *de; (de = readdir(d));) {
        if (de->d_name[0] == '.') continue;
        char path[PATH_MAX];
        struct stat sb;
        snprintf(path, sizeof path, "%s/%s", dir, de->d_name);
        if (stat(path, &sb) != 0 || (!S_ISDIR(sb.st_mode) && !is_scene_file(de->d_name))) continue;
        if (scene_leaves(c, de->d_name)) {
            fprintf(stderr,
                    "iird serve: scene %s: not listed: it leads outside the scenes directory %s "
                    "(--scenes-follow-links allows it)\n",
                    de->d_name, dir);
            continue;
        }
        if (*n + 2 > cap) {
            cap = 2 * cap + 8;
            char **grown = realloc(*names, cap * sizeof *grown);
            if (!grown) break;
            *names = grown;
        }
        (*names)[(*n)++] = strdup(de->d_name);
    }
    closedir(d);
    return true;
}

static char **scene_names(const iird_scene_cache *c)
{
    size_t n = 0;
    char **names = malloc(2 * sizeof *names);
    if (!names) return NULL;
    names[n++] = strdup("builtin");
    list_dir(c, &names, &n);
    qsort(names + 1, n - 1, sizeof *names, cmp_names);
    names[n] = NULL;
    return names;
}

/* ======================== the cache ======================== */

iird_scene_cache *iird_scene_cache_create(const char *scenes_dir, bool follow_links)
{
    iird_scene_cache *c = calloc(1, sizeof *c);
    if (!c) return NULL;
    c->dir = strdup(scenes_dir ? scenes_dir : ".");
    c->follow_links = follow_links;
    if (c->dir && !realpath(c->dir, c->dir_real)) c->dir_real[0] = '\0';
    c->names = c->dir ? scene_names(c) : NULL;
    pthread_mutex_init(&c->lock, NULL);
    pthread_cond_init(&c->loaded, NULL);
    if (!c->dir || !c->names) {
        iird_scene_cache_destroy(c);
        return NULL;
    }
    return c;
}

static void slot_free(iird_scene_cache *c, cache_slot *s)
{
    iird_budget_release(c->budget, &s->held);
    iir_rt_destroy(s->rt);
    iir_scene_destroy(s->scene);
    free(s);
}

void iird_scene_cache_destroy(iird_scene_cache *c)
{
    if (!c) return;
    for (cache_slot *s = c->slots, *next; s; s = next) {
        next = s->next;
        assert(s->refs == 0 && !s->loading);
        slot_free(c, s);
    }
    for (char **n = c->names; n && *n; n++) free(*n);
    free(c->names);
    free(c->dir);
    pthread_cond_destroy(&c->loaded);
    pthread_mutex_destroy(&c->lock);
    free(c);
}

const char *const *iird_scene_cache_names(const iird_scene_cache *c)
{
    return (const char *const *)c->names;
}

static bool has_locked(const iird_scene_cache *c, const char *name)
{
    for (char **n = c->names; *n; n++)
        if (!strcmp(*n, name)) return true;
    return false;
}

bool iird_scene_cache_has(const iird_scene_cache *c, const char *name)
{
    pthread_mutex_t *lock = (pthread_mutex_t *)&c->lock; /* guards names, not c's other fields */
    pthread_mutex_lock(lock);
    bool has = has_locked(c, name);
    pthread_mutex_unlock(lock);
    return has;
}

const char *iird_scene_cache_dir(const iird_scene_cache *c)
{
    return c->dir;
}

bool iird_scene_cache_in_dir(const iird_scene_cache *c, const iird_scene_entry *e)
{
    const cache_slot *s = (const cache_slot *)e;
    char path[PATH_MAX], real[PATH_MAX];
    if (!strcmp(s->key, "builtin")) return true;
    snprintf(path, sizeof path, "%s/%s", c->dir, e->name);
    return realpath(path, real) && !strcmp(real, s->key);
}

bool iird_scene_cache_folder(const iird_scene_cache *c, const iird_scene_entry *e, char *out,
                             size_t n)
{
    const cache_slot *s = (const cache_slot *)e;
    const char *slash = strrchr(s->key, '/'); /* a key other than builtin is a real path */
    out[0] = '\0';
    if (!strcmp(s->key, "builtin")) return false;
    if (c->dir_real[0] && iird_scene_cache_in_dir(c, e))
        snprintf(out, n, "%s", c->dir_real);
    else if (slash)
        snprintf(out, n, "%.*s", slash == s->key ? 1 : (int)(slash - s->key), s->key);
    return out[0] != '\0';
}

static const char *base_name(const char *path)
{
    size_t len = strlen(path);
    while (len > 1 && path[len - 1] == '/') len--;
    const char *end = path + len, *b = end;
    while (b > path && b[-1] != '/') b--;
    return b;
}

/* The cache key and the display name of what a caller asked for. */
static iir_status resolve(const iird_scene_cache *c, const char *arg, char *key, char *name,
                          iir_error *err)
{
    if (!arg || !strcmp(arg, "builtin")) {
        strcpy(key, "builtin");
        strcpy(name, "builtin");
        return IIR_OK;
    }
    if (c->startup && !strcmp(arg, c->startup->entry.name)) { /* the startup scene, wherever */
        snprintf(key, PATH_MAX, "%s", c->startup->key);
        snprintf(name, 130, "%s", c->startup->entry.name);
        return IIR_OK;
    }
    char path[PATH_MAX];
    if (iird_scene_cache_has(c, arg)) {
        /* a listed name: always the scenes folder's, never a file of the same name elsewhere */
        if (scene_leaves(c, arg))
            return iir_fail(err, IIR_ERR_INVALID,
                            "scene %s leads outside the scenes directory (a symbolic link): "
                            "refused (iird serve --scenes-follow-links allows it)",
                            arg);
        snprintf(path, sizeof path, "%s/%s", c->dir, arg);
        snprintf(name, 130, "%s", arg);
    } else {
        iir_status st = iir_scene_resolve(arg, c->dir, path, sizeof path, err);
        if (st != IIR_OK) return st;
        size_t len = strlen(base_name(arg));
        snprintf(name, 130, "%.*s", (int)(len < 129 ? len : 129), base_name(arg));
    }
    if (!realpath(path, key)) snprintf(key, PATH_MAX, "%s", path);
    return IIR_OK;
}

static cache_slot *find(iird_scene_cache *c, const char *key)
{
    for (cache_slot *s = c->slots; s; s = s->next)
        if (!strcmp(s->key, key)) return s;
    return NULL;
}

static void unlink_slot(iird_scene_cache *c, cache_slot *s)
{
    for (cache_slot **p = &c->slots; *p; p = &(*p)->next)
        if (*p == s) {
            *p = s->next;
            return;
        }
}

/* Loads the slot's scene with the lock released (its key is "builtin" or an existing path, so
 * nothing is looked up in a scenes folder); publishes the result under it. */
/* A camera iird chose (the scene has none) goes to the log, so the operator knows where it is. */
static void log_camera(const char *name, const iir_scene *scene)
{
    if (scene->camera_origin != IIR_CAMERA_OUTSIDE && scene->camera_origin != IIR_CAMERA_INSIDE)
        return;
    char line[512];
    iir_scene_describe_camera(scene, line, sizeof line);
    fprintf(stderr, "iird serve: scene %s: camera: %s\n", name, line);
}

static iir_status load_slot(iird_scene_cache *c, cache_slot *s, iir_error *err)
{
    iir_scene *scene = NULL;
    iir_rt *rt = NULL;
    pthread_mutex_unlock(&c->lock);
    iir_status st = iir_scene_open(s->key, NULL, &scene, &rt, err);
    char why[256];
    if (st == IIR_OK &&
        !iird_budget_reserve_scene(c->budget, &s->held, iir_scene_bytes(scene), why, sizeof why)) {
        st = iir_fail(err, IIR_ERR_UNSUPPORTED, "scene %s: %s", s->entry.name, why);
        iir_rt_destroy(rt);
        iir_scene_destroy(scene);
        scene = NULL, rt = NULL;
    }
    if (st == IIR_OK) {
        log_camera(s->entry.name, scene);
        char who[160];
        snprintf(who, sizeof who, "serve: scene %s", s->entry.name);
        iird_log_scene_notes(who, scene); /* what no method renders: docs/cli.md */
    }
    pthread_mutex_lock(&c->lock);
    s->loading = false;
    s->scene = scene;
    s->rt = rt;
    s->entry.scene = scene;
    s->entry.rt = rt;
    pthread_cond_broadcast(&c->loaded);
    return st;
}

/* The slot for key once no load of it is under way, or NULL (the lock is held). A slot whose load
 * failed is freed by its last waiter so the caller can try again. */
static cache_slot *find_loaded_locked(iird_scene_cache *c, const char *key)
{
    cache_slot *s = find(c, key);
    while (s && s->loading) {
        s->refs++; /* keep it while waiting */
        pthread_cond_wait(&c->loaded, &c->lock);
        s->refs--;
        if (!s->rt && s->refs == 0 && !s->loading) {
            unlink_slot(c, s);
            slot_free(c, s);
        }
        s = find(c, key);
    }
    return s;
}

/* A new slot for key, loaded with one reference (the lock is held; dropped while loading). */
static iir_status add_slot_locked(iird_scene_cache *c, const char *key, const char *name,
                                  cache_slot **out, iir_error *err)
{
    cache_slot *s = calloc(1, sizeof *s);
    if (!s) return iir_fail(err, IIR_ERR_NOMEM, "out of memory loading scene %s", name);
    snprintf(s->key, sizeof s->key, "%s", key);
    snprintf(s->entry.name, sizeof s->entry.name, "%s", name);
    s->loading = true;
    s->refs = 1;
    s->next = c->slots;
    c->slots = s;
    iir_status st = load_slot(c, s, err);
    if (st != IIR_OK && --s->refs == 0) {
        unlink_slot(c, s);
        slot_free(c, s);
    }
    *out = st == IIR_OK ? s : NULL;
    return st;
}

/* Replaces every path in msg (a word holding a '/': what a client must not learn of the server's
 * files) with the scene's name. */
static void hide_paths(char *msg, size_t cap, const char *name)
{
    char out[sizeof((iir_error *)0)->msg];
    size_t o = 0;
    for (const char *p = msg; *p && o + 1 < sizeof out;) {
        size_t w = strcspn(p, " \t\n'\"(),;");
        size_t keep = w > 0 && p[w - 1] == ':' ? w - 1 : w; /* "PATH: why" keeps its colon */
        bool path = memchr(p, '/', keep) != NULL;
        int k = path ? snprintf(out + o, sizeof out - o, "%s%.*s", name, (int)(w - keep), p + keep)
                     : snprintf(out + o, sizeof out - o, "%.*s", (int)w, p);
        o = k < 0 ? o : o + (size_t)k < sizeof out ? o + (size_t)k : sizeof out - 1;
        p += w;
        if (*p && o + 1 < sizeof out) out[o++] = *p++;
    }
    out[o] = '\0';
    snprintf(msg, cap, "%s", out);
}

/* A scene that does not load: the whole reason goes to the log, the caller (and so the client)
 * gets it with every path replaced by the scene's name. */
static iir_status failed(const char *name, iir_status st, iir_error *err)
{
    if (!err) return st;
    fprintf(stderr, "iird serve: scene %s: %s\n", name, err->msg);
    hide_paths(err->msg, sizeof err->msg, name);
    return st;
}

iir_status iird_scene_cache_acquire(iird_scene_cache *c, const char *name_or_path,
                                    const iird_scene_entry **out, iir_error *err)
{
    char key[PATH_MAX], name[130];
    *out = NULL;
    iir_status st = resolve(c, name_or_path, key, name, err);
    if (st != IIR_OK) return failed(name_or_path ? base_name(name_or_path) : "builtin", st, err);
    pthread_mutex_lock(&c->lock);
    cache_slot *s = find_loaded_locked(c, key);
    if (!s)
        st = add_slot_locked(c, key, name, &s, err);
    else if (!s->rt)
        st = iir_fail(err, IIR_ERR_INTERNAL, "scene %s failed to load", name);
    else
        s->refs++;
    pthread_mutex_unlock(&c->lock);
    if (st != IIR_OK) return failed(name, st, err);
    *out = &s->entry;
    return st;
}

void iird_scene_cache_ref(iird_scene_cache *c, const iird_scene_entry *e)
{
    pthread_mutex_lock(&c->lock);
    ((cache_slot *)e)->refs++;
    pthread_mutex_unlock(&c->lock);
}

void iird_scene_cache_release(iird_scene_cache *c, const iird_scene_entry *e)
{
    if (!e) return;
    cache_slot *s = (cache_slot *)e, *dead = NULL;
    pthread_mutex_lock(&c->lock);
    assert(s->refs > 0);
    if (--s->refs == 0 && !s->pinned) {
        unlink_slot(c, s);
        dead = s;
    }
    pthread_mutex_unlock(&c->lock);
    if (dead) slot_free(c, dead);
}

/* Adds name to the list (after "builtin", in order) unless it is there (the lock is held). */
static void list_name(iird_scene_cache *c, const char *name)
{
    size_t n = 0;
    while (c->names[n]) n++;
    char *copy = has_locked(c, name) ? NULL : strdup(name);
    char **grown = copy ? realloc(c->names, (n + 2) * sizeof *grown) : NULL;
    if (!grown) {
        free(copy);
        return;
    }
    grown[n] = copy;
    grown[n + 1] = NULL;
    qsort(grown + 1, n, sizeof *grown, cmp_names);
    c->names = grown;
}

void iird_scene_cache_pin(iird_scene_cache *c, const iird_scene_entry *e)
{
    pthread_mutex_lock(&c->lock);
    ((cache_slot *)e)->pinned = true;
    pthread_mutex_unlock(&c->lock);
}

void iird_scene_cache_set_startup(iird_scene_cache *c, const iird_scene_entry *e)
{
    iird_scene_cache_pin(c, e);
    c->startup = (const cache_slot *)e;
    pthread_mutex_lock(&c->lock);
    list_name(c, e->name);
    pthread_mutex_unlock(&c->lock);
}

void iird_scene_cache_add_name(iird_scene_cache *c, const char *name)
{
    pthread_mutex_lock(&c->lock);
    list_name(c, name);
    pthread_mutex_unlock(&c->lock);
}

void iird_scene_cache_set_budget(iird_scene_cache *c, iird_budget *b)
{
    c->budget = b;
}

size_t iird_scene_cache_loaded(iird_scene_cache *c, uint64_t *bytes)
{
    size_t n = 0;
    *bytes = 0;
    pthread_mutex_lock(&c->lock);
    for (cache_slot *s = c->slots; s; s = s->next)
        if (s->rt) n++, *bytes += iir_scene_bytes(s->scene);
    pthread_mutex_unlock(&c->lock);
    return n;
}
