/* scene_objtext.c -- a mesh file that is not binary glTF, and the MTL files it names, must be text
 * before assimp reads them: Debian's assimp 5.2 reads past the end of an MTL line that holds NUL
 * bytes and crashes (found by tests/fuzz/fuzz_scene; the inputs are kept in tests/fuzz/scene/).
 * assimp picks its importer by content as well as by extension (OBJ text named .gltf is read as
 * OBJ), so every file but a binary glTF (magic "glTF") is checked. Text formats (OBJ, MTL, glTF's
 * JSON) never hold NUL, so such a file is refused with its name and the byte's offset. Not parsing
 * OBJ. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene_objtext.h"

/* Whole file; NULL when it cannot be read (assimp then reports that itself). */
static char *read_all(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    char *buf = NULL;
    long n = fseek(f, 0, SEEK_END) == 0 ? ftell(f) : -1;
    if (n >= 0 && fseek(f, 0, SEEK_SET) == 0 && (buf = malloc((size_t)n + 1)))
        *len = fread(buf, 1, (size_t)n, f);
    fclose(f);
    if (buf) buf[*len] = '\0';
    return buf;
}

static iir_status refuse_nul(const char *path, const char *buf, size_t len, iir_error *err)
{
    const char *nul = memchr(buf, '\0', len);
    if (!nul) return IIR_OK;
    return iir_fail(err, IIR_ERR_FORMAT, "%s: byte %zu is NUL: not a text file (OBJ, MTL, glTF)",
                    path, (size_t)(nul - buf));
}

/* Checks every file named on one `mtllib` line (names relative to dir, space-separated). */
static iir_status check_mtllib(const char *dir, const char *line, iir_error *err)
{
    char names[1024];
    size_t n = strcspn(line, "\r\n");
    snprintf(names, sizeof names, "%.*s", (int)(n < sizeof names ? n : sizeof names - 1), line);
    iir_status st = IIR_OK;
    for (char *save = NULL, *tok = strtok_r(names, " \t", &save); tok && st == IIR_OK;
         tok = strtok_r(NULL, " \t", &save)) {
        char path[4096];
        snprintf(path, sizeof path, "%s%s", dir, tok);
        size_t len = 0;
        char *buf = read_all(path, &len);
        if (buf) st = refuse_nul(path, buf, len, err);
        free(buf);
    }
    return st;
}

iir_status iir_objtext_check(const char *obj_path, iir_error *err)
{
    size_t len = 0;
    char *obj = read_all(obj_path, &len);
    if (!obj) return IIR_OK;
    if (len >= 4 && !memcmp(obj, "glTF", 4)) return free(obj), IIR_OK; /* binary glTF */
    iir_status st = refuse_nul(obj_path, obj, len, err);
    char dir[4096];
    const char *slash = strrchr(obj_path, '/');
    int dlen = slash ? (int)(slash - obj_path + 1) : 0;
    snprintf(dir, sizeof dir, "%.*s", dlen, obj_path);
    for (const char *p = obj; st == IIR_OK && p && *p; p = strchr(p, '\n'), p = p ? p + 1 : p)
        if (!strncmp(p, "mtllib", 6) && (p[6] == ' ' || p[6] == '\t'))
            st = check_mtllib(dir, p + 7, err);
    free(obj);
    return st;
}
