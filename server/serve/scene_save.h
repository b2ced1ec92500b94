/* scene_save.h -- writing a scene sidecar into the scenes directory as a new scene, for `save`
 * with a name (docs/protocol.md): SCENES/NAME/NAME.scene.json, all at once and never over an
 * existing scene. Not building the sidecar (protocol.h, iird_sidecar_text) and not deciding who
 * may save (session_msg.c). */
#ifndef IIRD_SCENE_SAVE_H
#define IIRD_SCENE_SAVE_H

#include <stdbool.h>

#include "protocol/protocol.h"

/* Writes text as dir/name/name.scene.json. name must be a bare scene name (the protocol's
 * parser checked it). The folder is built under a hidden temporary name (".name.part-...") and
 * renamed into place without replacing anything, so the scene appears whole or not at all.
 * Returns false with err filled: bad_field naming save.name when dir/name exists (a scene, or
 * anything else), internal with the system's reason when writing fails; nothing is left behind.
 * Blocks for the write and an fsync of the file. */
bool iird_scene_save(const char *dir, const char *name, const char *text, iird_proto_error *err);

/* ---- what a save may write: a loadable base, a rate per address, a total ----
 * A saved scene is a folder NAME of the scenes directory whose NAME.scene.json names a "base"
 * (what save writes). The loader follows at most IIRD_SAVE_MAX_CHAIN such links, so a save
 * flattens: a scene iird saved (a sidecar of base, camera and lights alone) is replaced by its own
 * base, since the new sidecar's camera and lights replace all it adds. Service thread only. */

enum {
    IIRD_SAVE_MAX_CHAIN = 8,     /* sidecars based on sidecars the loader follows (scene.c) */
    IIRD_SAVED_DEFAULT = 200,    /* --max-saved-scenes */
    IIRD_SAVE_RATE_DEFAULT = 12, /* --save-rate: saves per address per minute (and burst) */
    IIRD_SAVED_LISTED = 20,      /* saved scenes listed in welcome and save replies (newest) */
};

/* The base a new scene saved from `scene` (a listed name) names: scene itself, or for a scene iird
 * saved, the first scene down its chain that is not one. False with err filled (unsupported on
 * save.name) when the new scene would start a chain the loader refuses. */
bool iird_save_base(const char *dir, const char *scene, char *base, size_t n,
                    iird_proto_error *err);

typedef struct iird_saves iird_saves;

/* The saved scenes of dir (counted now, oldest first by their sidecars' times) and the limits:
 * at most max_saved in dir, per_minute saves per client address. NULL when out of memory. */
iird_saves *iird_saves_create(const char *dir, int max_saved, int per_minute);
void iird_saves_destroy(iird_saves *s);
/* Whether a client at addr may save now (now_ms: iir_now_ms()); takes one of its tokens. False
 * with err filled: rate_limited past its rate, unsupported once dir holds max_saved scenes. */
bool iird_saves_admit(iird_saves *s, const char *addr, double now_ms, iird_proto_error *err);
/* Counts a scene just saved (the newest). */
void iird_saves_added(iird_saves *s, const char *name);
/* Saved scenes in dir. */
size_t iird_saves_count(const iird_saves *s);
/* What welcome and save replies list of names (NULL-terminated): every name but the saved scenes
 * older than the newest `max`; *more = the saved scenes left out (a `scenes` request lists all).
 * An array of pointers into names (free it, not them); NULL when out of memory. s may be NULL
 * (everything listed). */
const char **iird_saves_listed(const iird_saves *s, const char *const *names, size_t max,
                               size_t *more);

#endif
