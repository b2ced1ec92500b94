/* image_exr.c -- EXR through the OpenEXR 3 C API (OpenEXRCore): encoding into memory (an EXR
 * file holds the same bytes) and reading files; not other formats. */

/* Writing: one scanline part, channels R, G, B as 32-bit FLOAT, ZIP compression, data window at
 * (0, 0), into a growing memory buffer. Reading: part 0 of a flat scanline or tiled file (level 0
 * only), channels R, G and B of any pixel type (HALF, FLOAT, UINT) converted to float by the
 * library's decoder; the data window may start anywhere. We give the library our own stream so
 * that its error messages land in a per-call buffer (its default stream keeps its file handle in
 * the user data pointer). */
#include "iir/image.h"
#include "image_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <openexr.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* ---- the stream and its error capture ------------------------------------------------------- */

typedef struct exr_stream {
    int fd;           /* reading: the file */
    uint8_t *data;    /* writing: the bytes so far (malloc'ed), ... */
    size_t size, cap; /* ... how many, and the room allocated */
    char msg[256];    /* the library's first error message for this call, "" if none */
} exr_stream;

static void on_exr_error(exr_const_context_t ctx, exr_result_t code, const char *msg)
{
    void *ud = NULL;
    (void)code;
    if (!ctx || exr_get_user_data(ctx, &ud) != EXR_ERR_SUCCESS || !ud) return;
    exr_stream *s = ud;
    if (!s->msg[0]) snprintf(s->msg, sizeof s->msg, "%s", msg);
}

static int64_t stream_read(exr_const_context_t ctx, void *ud, void *buf, uint64_t sz,
                           uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    exr_stream *s = ud;
    uint64_t done = 0;
    while (done < sz) {
        ssize_t n = pread(s->fd, (char *)buf + done, (size_t)(sz - done), (off_t)(offset + done));
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) {
            if (error_cb) error_cb(ctx, EXR_ERR_READ_IO, "read failed: %s", strerror(errno));
            return -1;
        }
        if (n == 0) break;
        done += (uint64_t)n;
    }
    return (int64_t)done;
}

static int64_t stream_size(exr_const_context_t ctx, void *ud)
{
    exr_stream *s = ud;
    struct stat st;
    (void)ctx;
    return fstat(s->fd, &st) == 0 ? (int64_t)st.st_size : -1;
}

/* Room for at least `need` bytes in the memory being written. */
static bool stream_reserve(exr_stream *s, uint64_t need)
{
    if (need <= s->cap) return true;
    if (need > SIZE_MAX / 2) return false;
    size_t cap = s->cap ? 2 * s->cap : 64 * 1024;
    while (cap < need) cap *= 2;
    uint8_t *grown = realloc(s->data, cap);
    if (!grown) return false;
    s->data = grown;
    s->cap = cap;
    return true;
}

/* pwrite into memory: a gap before offset reads as zeros, as in a file. */
static int64_t stream_write(exr_const_context_t ctx, void *ud, const void *buf, uint64_t sz,
                            uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    exr_stream *s = ud;
    if (offset > UINT64_MAX - sz || !stream_reserve(s, offset + sz)) {
        if (error_cb)
            error_cb(ctx, EXR_ERR_OUT_OF_MEMORY, "out of memory for %llu bytes",
                     (unsigned long long)(offset + sz));
        return -1;
    }
    if (offset > s->size) memset(s->data + s->size, 0, (size_t)offset - s->size);
    memcpy(s->data + offset, buf, (size_t)sz);
    if (offset + sz > s->size) s->size = (size_t)(offset + sz);
    return (int64_t)sz;
}

static exr_context_initializer_t stream_initializer(exr_stream *s)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = on_exr_error;
    init.user_data = s;
    init.read_fn = stream_read;
    init.size_fn = stream_size;
    init.write_fn = stream_write;
    init.max_image_width = IIR_IMAGE_MAX_DIM;
    init.max_image_height = IIR_IMAGE_MAX_DIM;
    return init;
}

/* Turns a library result into a status and a message naming the file (path NULL: encoding into
 * memory, where a failed write can only mean out of memory). Reading a file we could open, a
 * short read means the file is cut short, so it counts as a format error. */
static iir_status exr_failure(iir_error *err, const char *what, const char *path,
                              const exr_stream *s, exr_result_t rc, int writing)
{
    iir_status st = writing ? IIR_ERR_INTERNAL : IIR_ERR_FORMAT;
    if (rc == EXR_ERR_OUT_OF_MEMORY || (writing && rc == EXR_ERR_WRITE_IO)) st = IIR_ERR_NOMEM;
    if (rc == EXR_ERR_FILE_ACCESS) st = IIR_ERR_IO;
    if (rc == EXR_ERR_FEATURE_NOT_IMPLEMENTED) st = IIR_ERR_UNSUPPORTED;
    const char *why = s->msg[0] ? s->msg : exr_get_default_error_message(rc);
    const char *hint = !writing && rc == EXR_ERR_READ_IO ? " (is the file truncated?)" : "";
    return iir_fail(err, st, "%s%s%s: %s%s", what, path ? " " : "", path ? path : "", why, hint);
}

/* ---- reading -------------------------------------------------------------------------------- */

/* Where decoded pixels go: the image and the data window's origin. */
typedef struct exr_target {
    iir_image *img;
    int min_x, min_y;
} exr_target;

static int rgb_component(const char *name)
{
    if (strcmp(name, "R") == 0) return 0;
    if (strcmp(name, "G") == 0) return 1;
    if (strcmp(name, "B") == 0) return 2;
    return -1;
}

/* Points R, G, B of a chunk whose top-left pixel is (x0, y0) in the image (not in the data
 * window) at their place in the interleaved float image; skips the other channels. */
static void point_decoder(exr_decode_pipeline_t *dec, int x0, int y0, const exr_target *t)
{
    iir_vec3 *first = iir_image_at(t->img, x0, y0);
    for (int c = 0; c < dec->channel_count; c++) {
        exr_coding_channel_info_t *ch = &dec->channels[c];
        int comp = rgb_component(ch->channel_name);
        if (comp < 0 || ch->height == 0) {
            ch->decode_to_ptr = NULL;
            continue;
        }
        ch->decode_to_ptr = (uint8_t *)first + (size_t)comp * sizeof(float);
        ch->user_pixel_stride = (int32_t)sizeof(iir_vec3);
        ch->user_line_stride = (int32_t)(sizeof(iir_vec3) * (size_t)t->img->width);
        ch->user_data_type = EXR_PIXEL_FLOAT;
        ch->user_bytes_per_element = (int16_t)sizeof(float);
    }
}

static exr_result_t decode_chunk(exr_const_context_t ctx, const exr_chunk_info_t *ci, int x0,
                                 int y0, exr_decode_pipeline_t *dec, const exr_target *t)
{
    int first = dec->channels == NULL;
    exr_result_t rc =
        first ? exr_decoding_initialize(ctx, 0, ci, dec) : exr_decoding_update(ctx, 0, ci, dec);
    if (rc != EXR_ERR_SUCCESS) return rc;
    point_decoder(dec, x0, y0, t);
    if (first && (rc = exr_decoding_choose_default_routines(ctx, 0, dec)) != EXR_ERR_SUCCESS)
        return rc;
    return exr_decoding_run(ctx, 0, dec);
}

static exr_result_t decode_scanlines(exr_const_context_t ctx, exr_decode_pipeline_t *dec,
                                     const exr_target *t)
{
    int32_t lines = 0;
    exr_result_t rc = exr_get_scanlines_per_chunk(ctx, 0, &lines);
    if (rc == EXR_ERR_SUCCESS && lines < 1) rc = EXR_ERR_INVALID_ATTR;
    int max_y = t->min_y + t->img->height - 1;
    for (int y = t->min_y; rc == EXR_ERR_SUCCESS && y <= max_y; y += lines) {
        exr_chunk_info_t ci;
        rc = exr_read_scanline_chunk_info(ctx, 0, y, &ci);
        if (rc == EXR_ERR_SUCCESS) rc = decode_chunk(ctx, &ci, 0, ci.start_y - t->min_y, dec, t);
    }
    return rc;
}

/* Level (0, 0) of a tiled part; mip and rip levels below it are ignored. A tile's chunk info
 * gives its tile indices in start_x/start_y, not pixels. */
static exr_result_t decode_tiles(exr_const_context_t ctx, exr_decode_pipeline_t *dec,
                                 const exr_target *t)
{
    int32_t tw = 0, th = 0;
    exr_result_t rc = exr_get_tile_sizes(ctx, 0, 0, 0, &tw, &th);
    if (rc == EXR_ERR_SUCCESS && (tw < 1 || th < 1)) rc = EXR_ERR_INVALID_ATTR;
    if (rc != EXR_ERR_SUCCESS) return rc;
    int nx = (t->img->width + tw - 1) / tw, ny = (t->img->height + th - 1) / th;
    for (int ty = 0; rc == EXR_ERR_SUCCESS && ty < ny; ty++) {
        for (int tx = 0; rc == EXR_ERR_SUCCESS && tx < nx; tx++) {
            exr_chunk_info_t ci;
            rc = exr_read_tile_chunk_info(ctx, 0, tx, ty, 0, 0, &ci);
            if (rc == EXR_ERR_SUCCESS) rc = decode_chunk(ctx, &ci, tx * tw, ty * th, dec, t);
        }
    }
    return rc;
}

/* Checks that R, G and B exist at full resolution; lists the channels found otherwise. */
static iir_status check_channels(const exr_attr_chlist_t *chl, const char *path, iir_error *err)
{
    int found[3] = {0, 0, 0};
    char names[160] = "";
    for (int i = 0; i < chl->num_channels; i++) {
        const exr_attr_chlist_entry_t *e = &chl->entries[i];
        int comp = rgb_component(e->name.str);
        if (comp >= 0 && (e->x_sampling != 1 || e->y_sampling != 1))
            return iir_fail(err, IIR_ERR_UNSUPPORTED,
                            "EXR %s: channel %s is subsampled (%dx%d); iir reads full-resolution "
                            "R, G, B only",
                            path, e->name.str, e->x_sampling, e->y_sampling);
        if (comp >= 0) found[comp] = 1;
        size_t len = strlen(names);
        snprintf(names + len, sizeof names - len, "%s%s", i ? ", " : "", e->name.str);
    }
    for (int c = 0; c < 3; c++)
        if (!found[c])
            return iir_fail(err, IIR_ERR_FORMAT,
                            "EXR %s has no %c channel (channels: %s); iir reads R, G and B", path,
                            "RGB"[c], names[0] ? names : "none");
    return IIR_OK;
}

/* Validates part 0 and finds its data window. */
static iir_status inspect_part(exr_context_t ctx, const char *path, const exr_stream *s,
                               exr_storage_t *storage, exr_attr_box2i_t *dw, iir_error *err)
{
    const exr_attr_chlist_t *chl = NULL;
    exr_result_t rc = exr_get_storage(ctx, 0, storage);
    if (rc == EXR_ERR_SUCCESS) rc = exr_get_data_window(ctx, 0, dw);
    if (rc == EXR_ERR_SUCCESS) rc = exr_get_channels(ctx, 0, &chl);
    if (rc != EXR_ERR_SUCCESS) return exr_failure(err, "cannot read EXR", path, s, rc, 0);
    if (*storage != EXR_STORAGE_SCANLINE && *storage != EXR_STORAGE_TILED)
        return iir_fail(err, IIR_ERR_UNSUPPORTED,
                        "EXR %s holds deep data; iir reads flat scanline or tiled images", path);
    int64_t w = (int64_t)dw->max.x - dw->min.x + 1, h = (int64_t)dw->max.y - dw->min.y + 1;
    if (w < 1 || w > IIR_IMAGE_MAX_DIM || h < 1 || h > IIR_IMAGE_MAX_DIM)
        return iir_fail(err, IIR_ERR_FORMAT, "EXR %s: size %lldx%lld is outside 1..%d", path,
                        (long long)w, (long long)h, IIR_IMAGE_MAX_DIM);
    return check_channels(chl, path, err);
}

static iir_status read_part(exr_context_t ctx, const char *path, const exr_stream *s,
                            iir_image **out, iir_error *err)
{
    exr_storage_t storage;
    exr_attr_box2i_t dw;
    iir_status st = inspect_part(ctx, path, s, &storage, &dw, err);
    if (st != IIR_OK) return st;
    exr_target t = {iir_image_create(dw.max.x - dw.min.x + 1, dw.max.y - dw.min.y + 1), dw.min.x,
                    dw.min.y};
    if (!t.img) return iir_fail(err, IIR_ERR_NOMEM, "cannot read EXR %s: out of memory", path);
    exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
    exr_result_t rc = storage == EXR_STORAGE_TILED ? decode_tiles(ctx, &dec, &t)
                                                   : decode_scanlines(ctx, &dec, &t);
    exr_decoding_destroy(ctx, &dec);
    if (rc != EXR_ERR_SUCCESS) {
        iir_image_destroy(t.img);
        return exr_failure(err, "cannot decode EXR", path, s, rc, 0);
    }
    *out = t.img;
    return IIR_OK;
}

iir_status iir_image_read_exr(const char *path, iir_image **out, iir_error *err)
{
    *out = NULL;
    exr_stream s = {.fd = open(path, O_RDONLY | O_CLOEXEC)};
    if (s.fd < 0) return iir_fail(err, IIR_ERR_IO, "cannot open EXR %s: %s", path, strerror(errno));
    if (stream_size(NULL, &s) == 0) {
        close(s.fd);
        return iir_fail(err, IIR_ERR_FORMAT, "EXR %s is empty", path);
    }
    exr_context_initializer_t init = stream_initializer(&s);
    exr_context_t ctx = NULL;
    exr_result_t rc = exr_start_read(&ctx, path, &init);
    iir_status st = rc == EXR_ERR_SUCCESS ? read_part(ctx, path, &s, out, err)
                                          : exr_failure(err, "cannot read EXR", path, &s, rc, 0);
    exr_finish(&ctx);
    close(s.fd);
    return st;
}

/* ---- writing -------------------------------------------------------------------------------- */

static exr_result_t define_header(exr_context_t ctx, const iir_image *img)
{
    int part = 0;
    exr_result_t rc = exr_add_part(ctx, NULL, EXR_STORAGE_SCANLINE, &part);
    if (rc == EXR_ERR_SUCCESS)
        rc = exr_initialize_required_attr_simple(ctx, part, img->width, img->height,
                                                 EXR_COMPRESSION_ZIP);
    static const char *const names[3] = {"B", "G", "R"};
    for (int c = 0; c < 3 && rc == EXR_ERR_SUCCESS; c++)
        rc = exr_add_channel(ctx, part, names[c], EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC, 1,
                             1);
    if (rc == EXR_ERR_SUCCESS) rc = exr_write_header(ctx);
    return rc;
}

/* Feeds the encoder rows [ci->start_y, ci->start_y + ci->height) of img. */
static void point_encoder(exr_encode_pipeline_t *enc, const exr_chunk_info_t *ci,
                          const iir_image *img)
{
    const iir_vec3 *first = &img->pixels[(size_t)ci->start_y * (size_t)img->width];
    for (int c = 0; c < enc->channel_count; c++) {
        exr_coding_channel_info_t *ch = &enc->channels[c];
        int comp = rgb_component(ch->channel_name);
        ch->encode_from_ptr = (const uint8_t *)first + (size_t)comp * sizeof(float);
        ch->user_pixel_stride = (int32_t)sizeof(iir_vec3);
        ch->user_line_stride = (int32_t)(sizeof(iir_vec3) * (size_t)img->width);
        ch->user_data_type = EXR_PIXEL_FLOAT;
        ch->user_bytes_per_element = (int16_t)sizeof(float);
    }
}

static exr_result_t encode_chunk(exr_context_t ctx, int y, exr_encode_pipeline_t *enc,
                                 const iir_image *img)
{
    exr_chunk_info_t ci;
    exr_result_t rc = exr_write_scanline_chunk_info(ctx, 0, y, &ci);
    if (rc != EXR_ERR_SUCCESS) return rc;
    int first = enc->channels == NULL;
    rc = first ? exr_encoding_initialize(ctx, 0, &ci, enc) : exr_encoding_update(ctx, 0, &ci, enc);
    if (rc != EXR_ERR_SUCCESS) return rc;
    point_encoder(enc, &ci, img);
    if (first && (rc = exr_encoding_choose_default_routines(ctx, 0, enc)) != EXR_ERR_SUCCESS)
        return rc;
    return exr_encoding_run(ctx, 0, enc);
}

static exr_result_t write_pixels(exr_context_t ctx, const iir_image *img)
{
    int32_t lines = 0;
    exr_result_t rc = exr_get_scanlines_per_chunk(ctx, 0, &lines);
    if (rc == EXR_ERR_SUCCESS && lines < 1) rc = EXR_ERR_INVALID_ATTR;
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    for (int y = 0; rc == EXR_ERR_SUCCESS && y < img->height; y += lines)
        rc = encode_chunk(ctx, y, &enc, img);
    exr_encoding_destroy(ctx, &enc);
    return rc;
}

/* The EXR's bytes; path (NULL: none) only names the file in messages. */
static iir_status encode_exr(const iir_image *img, const char *path, uint8_t **data, size_t *size,
                             iir_error *err)
{
    *data = NULL;
    *size = 0;
    exr_stream s = {.fd = -1};
    exr_context_initializer_t init = stream_initializer(&s);
    exr_context_t ctx = NULL;
    exr_result_t rc =
        exr_start_write(&ctx, path ? path : "(memory)", EXR_WRITE_FILE_DIRECTLY, &init);
    if (rc == EXR_ERR_SUCCESS) rc = define_header(ctx, img);
    if (rc == EXR_ERR_SUCCESS) rc = write_pixels(ctx, img);
    exr_result_t finish_rc = exr_finish(&ctx); /* writes the chunk offset table */
    if (rc == EXR_ERR_SUCCESS) rc = finish_rc;
    if (rc != EXR_ERR_SUCCESS) {
        free(s.data);
        return exr_failure(err, path ? "cannot write EXR" : "cannot encode EXR", path, &s, rc, 1);
    }
    uint8_t *fit = s.size ? realloc(s.data, s.size) : NULL; /* gives back the growth's slack */
    *data = fit ? fit : s.data;
    *size = s.size;
    return IIR_OK;
}

iir_status iir_image_encode_exr(const iir_image *img, uint8_t **data, size_t *size, iir_error *err)
{
    return encode_exr(img, NULL, data, size, err);
}

iir_status iir_image_write_exr(const iir_image *img, const char *path, iir_error *err)
{
    uint8_t *data = NULL;
    size_t size = 0;
    iir_status st = encode_exr(img, path, &data, &size, err);
    if (st == IIR_OK) st = iir_image_save_bytes(path, "EXR", data, size, err);
    free(data);
    return st;
}
