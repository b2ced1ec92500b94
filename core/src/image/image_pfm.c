/* image_pfm.c -- reads and writes Portable Float Maps directly; not other formats. */

/* Format: an ASCII header "PF" (RGB) or "Pf" (grey), width, height and a scale, each separated by
 * whitespace, then exactly one whitespace byte and width*height*channels 32-bit floats, rows from
 * the bottom of the image to the top. A negative scale means little-endian data, a positive one
 * big-endian; its magnitude is ignored. We always write RGB, little-endian, scale -1. */
#include "iir/image.h"

#include "image_internal.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- byte order ----------------------------------------------------------------------------- */

static void put_f32_le(uint8_t *p, float v)
{
    uint32_t u;
    memcpy(&u, &v, sizeof u);
    p[0] = (uint8_t)u;
    p[1] = (uint8_t)(u >> 8);
    p[2] = (uint8_t)(u >> 16);
    p[3] = (uint8_t)(u >> 24);
}

static float get_f32(const uint8_t *p, int little_endian)
{
    uint32_t u =
        little_endian
            ? (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24
            : (uint32_t)p[3] | (uint32_t)p[2] << 8 | (uint32_t)p[1] << 16 | (uint32_t)p[0] << 24;
    float v;
    memcpy(&v, &u, sizeof v);
    return v;
}

/* ---- writing -------------------------------------------------------------------------------- */

/* Writes the header and the rows bottom to top; returns 0 on a short write. */
static int write_pfm_body(FILE *f, const iir_image *img, uint8_t *row)
{
    if (fprintf(f, "PF\n%d %d\n-1.0\n", img->width, img->height) < 0) return 0;
    size_t row_bytes = (size_t)img->width * 12;
    for (int y = img->height - 1; y >= 0; y--) {
        const iir_vec3 *src = &img->pixels[(size_t)y * (size_t)img->width];
        for (int x = 0; x < img->width; x++) {
            put_f32_le(row + 12 * (size_t)x + 0, src[x].x);
            put_f32_le(row + 12 * (size_t)x + 4, src[x].y);
            put_f32_le(row + 12 * (size_t)x + 8, src[x].z);
        }
        if (fwrite(row, 1, row_bytes, f) != row_bytes) return 0;
    }
    return 1;
}

iir_status iir_image_write_pfm(const iir_image *img, const char *path, iir_error *err)
{
    uint8_t *row = malloc((size_t)img->width * 12);
    if (!row) return iir_fail(err, IIR_ERR_NOMEM, "cannot write PFM %s: out of memory", path);
    FILE *f = fopen(path, "wb");
    if (!f) {
        int e = errno;
        free(row);
        return iir_fail(err, IIR_ERR_IO, "cannot create PFM %s: %s", path, strerror(e));
    }
    int ok = write_pfm_body(f, img, row);
    int e = errno;
    free(row);
    if (fclose(f) != 0 && ok) {
        ok = 0;
        e = errno;
    }
    if (!ok) {
        remove(path);
        return iir_fail(err, IIR_ERR_IO, "cannot write PFM %s: %s", path, strerror(e));
    }
    return IIR_OK;
}

/* ---- reading -------------------------------------------------------------------------------- */

typedef struct pfm_header {
    int channels; /* 3 for "PF", 1 for "Pf" */
    int width, height;
    int little_endian;
} pfm_header;

/* Reads one whitespace-delimited header token and consumes the single whitespace byte after it.
 * Returns 0 at end of file or when the token does not fit in buf. */
static int read_token(FILE *f, char *buf, size_t cap)
{
    int c;
    do c = fgetc(f);
    while (c == ' ' || c == '\t' || c == '\n' || c == '\r');
    size_t n = 0;
    while (c != EOF && c != ' ' && c != '\t' && c != '\n' && c != '\r') {
        if (n + 1 >= cap) return 0;
        buf[n++] = (char)c;
        c = fgetc(f);
    }
    buf[n] = '\0';
    return n > 0 && c != EOF;
}

/* Parses a width or height: 1 when s is an integer in [1, IIR_IMAGE_MAX_DIM], 0 when it is an
 * integer outside that range (however large), -1 when it is not an integer. */
static int parse_dim(const char *s, int *out)
{
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (end == s || *end) return -1;
    if (errno == ERANGE || v < 1 || v > IIR_IMAGE_MAX_DIM) return 0;
    *out = (int)v;
    return 1;
}

static iir_status check_dims(const char *path, const char *w, const char *h, pfm_header *hdr,
                             iir_error *err)
{
    int rw = parse_dim(w, &hdr->width), rh = parse_dim(h, &hdr->height);
    if (rw < 0 || rh < 0)
        return iir_fail(err, IIR_ERR_FORMAT, "PFM %s: size \"%.31s x %.31s\" is not two integers",
                        path, w, h);
    if (rw == 0 || rh == 0)
        return iir_fail(err, IIR_ERR_FORMAT,
                        "PFM %s: size %.31s x %.31s is outside the supported 1..%d per side", path,
                        w, h, IIR_IMAGE_MAX_DIM);
    return IIR_OK;
}

static iir_status read_pfm_header(FILE *f, const char *path, pfm_header *h, iir_error *err)
{
    char magic[8], w[32], hgt[32], scale[64];
    int first = fgetc(f);
    if (first == EOF)
        return ferror(f)
                   ? iir_fail(err, IIR_ERR_IO, "cannot read PFM %s: %s", path, strerror(errno))
                   : iir_fail(err, IIR_ERR_FORMAT, "PFM %s is empty", path);
    ungetc(first, f);
    if (!read_token(f, magic, sizeof magic) || (strcmp(magic, "PF") && strcmp(magic, "Pf")))
        return iir_fail(err, IIR_ERR_FORMAT, "%s is not a PFM file (it must start with PF or Pf)",
                        path);
    h->channels = magic[1] == 'F' ? 3 : 1;
    if (!read_token(f, w, sizeof w) || !read_token(f, hgt, sizeof hgt) ||
        !read_token(f, scale, sizeof scale))
        return iir_fail(err, IIR_ERR_FORMAT,
                        "PFM %s: header is cut short (expected width, height and scale)", path);
    iir_status st = check_dims(path, w, hgt, h, err);
    if (st != IIR_OK) return st;
    char *end;
    double s = strtod(scale, &end);
    if (*end || end == scale || !isfinite(s) || s == 0.0)
        return iir_fail(err, IIR_ERR_FORMAT,
                        "PFM %s: scale \"%.63s\" is not a finite non-zero number", path, scale);
    h->little_endian = s < 0.0;
    return IIR_OK;
}

/* Reads the rows (bottom first) into img, converting grey to RGB. */
static iir_status read_pfm_rows(FILE *f, const char *path, const pfm_header *h, iir_image *img,
                                uint8_t *row, iir_error *err)
{
    size_t row_bytes = (size_t)h->width * (size_t)h->channels * 4;
    for (int r = 0; r < h->height; r++) {
        size_t got = fread(row, 1, row_bytes, f);
        if (got != row_bytes)
            return iir_fail(err, IIR_ERR_FORMAT,
                            "PFM %s is truncated: pixel data ends in row %d of %d (%dx%d, %s)",
                            path, r + 1, h->height, h->width, h->height,
                            h->channels == 3 ? "RGB" : "grey");
        iir_vec3 *dst = iir_image_at(img, 0, h->height - 1 - r);
        for (int x = 0; x < h->width; x++) {
            const uint8_t *p = row + (size_t)x * (size_t)h->channels * 4;
            float c0 = get_f32(p, h->little_endian);
            dst[x] = h->channels == 3 ? iir_v3(c0, get_f32(p + 4, h->little_endian),
                                               get_f32(p + 8, h->little_endian))
                                      : iir_v3s(c0);
        }
    }
    return IIR_OK;
}

/* Bytes from the current position to the end of f, or -1 when f cannot seek (a pipe). */
static long bytes_left(FILE *f)
{
    long at = ftell(f);
    if (at < 0 || fseek(f, 0, SEEK_END) != 0) return -1;
    long end = ftell(f);
    if (fseek(f, at, SEEK_SET) != 0 || end < at) return -1;
    return end - at;
}

static iir_status read_pfm_file(FILE *f, const char *path, iir_image **out, iir_error *err)
{
    pfm_header h = {0, 0, 0, 0};
    iir_status st = read_pfm_header(f, path, &h, err);
    if (st != IIR_OK) return st;
    /* a short file is refused before its header's size is allocated (up to 3 GiB) */
    size_t need = (size_t)h.width * (size_t)h.height * (size_t)h.channels * 4;
    long left = bytes_left(f);
    if (left >= 0 && (size_t)left < need)
        return iir_fail(err, IIR_ERR_FORMAT,
                        "PFM %s is truncated: %ld bytes of pixel data for %dx%d %s (%zu needed)",
                        path, left, h.width, h.height, h.channels == 3 ? "RGB" : "grey", need);
    iir_image *img = iir_image_create(h.width, h.height);
    uint8_t *row = malloc((size_t)h.width * (size_t)h.channels * 4);
    if (!img || !row) {
        st = iir_fail(err, IIR_ERR_NOMEM, "cannot read PFM %s: out of memory for %dx%d pixels",
                      path, h.width, h.height);
    } else {
        st = read_pfm_rows(f, path, &h, img, row, err);
    }
    free(row);
    if (st != IIR_OK) {
        iir_image_destroy(img);
        return st;
    }
    *out = img;
    return IIR_OK;
}

iir_status iir_image_read_pfm_memory(const uint8_t *data, size_t size, const char *name,
                                     iir_image **out, iir_error *err)
{
    *out = NULL;
    static const uint8_t empty[1];
    /* fmemopen refuses a size of 0 on some C libraries: an empty file is then one past its end */
    FILE *f = fmemopen((void *)(size ? data : empty), size ? size : 1, "rb");
    if (!f) return iir_fail(err, IIR_ERR_NOMEM, "cannot read PFM %s: %s", name, strerror(errno));
    if (!size) fgetc(f);
    iir_status st = read_pfm_file(f, name, out, err);
    fclose(f);
    return st;
}

iir_status iir_image_read_pfm(const char *path, iir_image **out, iir_error *err)
{
    *out = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) return iir_fail(err, IIR_ERR_IO, "cannot open PFM %s: %s", path, strerror(errno));
    iir_status st = read_pfm_file(f, path, out, err);
    fclose(f);
    return st;
}
