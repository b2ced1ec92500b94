/* scene_cache.h -- the scenes the daemon has in memory: each loaded once with its ray tracer,
 * shared read-only by every session that shows it, reference-counted and freed when the last
 * session leaves (the startup scene stays pinned). Also the list of scene names a client may ask
 * for. Not sessions and not how a scene file is parsed (scene.h).
 *
 * Threads: acquire and release may be called from any thread (render workers load scenes, the
 * service thread counts them); one mutex guards the table. Loading happens outside the lock, so
 * a session loading a large scene does not stall the others; a second session asking for a scene
 * that is being loaded waits for that load instead of starting its own. */
#ifndef IIRD_SCENE_CACHE_H
#define IIRD_SCENE_CACHE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "iir/rt.h"
#include "iir/scene.h"
#include "iir/status.h"

/* A loaded scene. Read-only for holders of a reference. */
typedef struct iird_scene_entry {
    char name[130]; /* what clients see: "builtin", a name in the scenes directory, or for a
                       startup scene given as a path its base name */
    const iir_scene *scene;
    const iir_rt *rt;
} iird_scene_entry;

typedef struct iird_scene_cache iird_scene_cache;

/* An empty cache over scenes_dir (copied); lists the names in scenes_dir once, now. Unless
 * follow_links, a name that resolves (symbolic links followed) outside scenes_dir, or whose
 * folder holds a file that does, is neither listed nor loaded. NULL on out-of-memory. */
iird_scene_cache *iird_scene_cache_create(const char *scenes_dir, bool follow_links);
/* Frees every scene still loaded; all references must have been released (asserted). */
void iird_scene_cache_destroy(iird_scene_cache *c);

/* The names a client may load, NULL-terminated, sorted: "builtin" then the folders (and scene
 * files) of the scenes directory, and scenes saved since. Service thread only: valid until the
 * next iird_scene_cache_add_name. */
const char *const *iird_scene_cache_names(const iird_scene_cache *c);
/* True when name is one of iird_scene_cache_names. Any thread. */
bool iird_scene_cache_has(const iird_scene_cache *c, const char *name);
/* Lists a scene just saved into the scenes directory (a folder of that name), for every session
 * from now on. Service thread only; out of memory leaves the list as it was. */
void iird_scene_cache_add_name(iird_scene_cache *c, const char *name);
/* The scenes directory, as given. */
const char *iird_scene_cache_dir(const iird_scene_cache *c);
/* The folder, absolute, in which e's name finds e (what a recording names as its "scenes", for
 * `iird render --anim`): the scenes directory for a scene in it, else the folder holding a scene
 * given as a path; false for the built-in box, which needs none (out is then ""). Any thread. */
bool iird_scene_cache_folder(const iird_scene_cache *c, const iird_scene_entry *e, char *out,
                             size_t n);
/* True when e is the built-in box or the scene of its name in the scenes directory (not a
 * startup scene given as a path elsewhere), so a sidecar can name it as its "base". */
bool iird_scene_cache_in_dir(const iird_scene_cache *c, const iird_scene_entry *e);

/* A new reference to scene `name_or_path`, loading it if no session holds it (this can take
 * seconds for a large scene). "builtin" (or NULL) is the built-in Cornell box; any other text is
 * resolved as iir_scene_open does. On error returns its status with err filled and *out NULL:
 * the reason is logged on stderr whole, and err's message has every path in it replaced by the
 * scene's name (clients see it). */
iir_status iird_scene_cache_acquire(iird_scene_cache *c, const char *name_or_path,
                                    const iird_scene_entry **out, iir_error *err);
/* Another reference to a scene the caller holds (or that is pinned). */
void iird_scene_cache_ref(iird_scene_cache *c, const iird_scene_entry *e);
/* Drops a reference from acquire or ref; the scene is freed with its last one unless pinned. NULL
 * is ignored. */
void iird_scene_cache_release(iird_scene_cache *c, const iird_scene_entry *e);
/* Keeps e loaded even with no session on it (the startup scene). Takes no reference. */
void iird_scene_cache_pin(iird_scene_cache *c, const iird_scene_entry *e);
/* Pins e as the startup scene and lists its name, so that clients can pick it again even when
 * it was given as a path outside the scenes directory (its name then means it, not a scene of
 * the directory with the same name). Before any session exists. */
void iird_scene_cache_set_startup(iird_scene_cache *c, const iird_scene_entry *e);

/* Counts each scene loaded from now on in b (its bytes, while it is in memory): a scene that does
 * not fit is refused. Before any acquire; b NULL: no budget. */
struct iird_budget;
void iird_scene_cache_set_budget(iird_scene_cache *c, struct iird_budget *b);

/* Scenes in memory now, and the bytes they hold (iir_scene_bytes: geometry, materials and
 * decoded textures; not the ray tracers' BVHs, which Embree does not report). */
size_t iird_scene_cache_loaded(iird_scene_cache *c, uint64_t *bytes);

#endif
