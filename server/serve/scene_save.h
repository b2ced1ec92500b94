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

#endif
