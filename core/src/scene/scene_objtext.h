/* scene_objtext.h -- refusing OBJ/MTL files that are not text before assimp reads them
 * (scene_objtext.c). */
#ifndef IIR_SCENE_OBJTEXT_H
#define IIR_SCENE_OBJTEXT_H

#include "iir/status.h"

/* IIR_ERR_FORMAT naming the file when obj_path (unless it is binary glTF) or an MTL file its
 * `mtllib` lines name holds a NUL byte; IIR_OK otherwise (also for files that cannot be read:
 * assimp reports those). */
iir_status iir_objtext_check(const char *obj_path, iir_error *err);

#endif
