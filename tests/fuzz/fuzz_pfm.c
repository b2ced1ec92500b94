/* fuzz_pfm.c -- libFuzzer target for the PFM reader (core/src/image/image_pfm.c): the bytes are a
 * file; the reader must refuse it with a message or return an image of the header's size.
 * Dimensions are capped by IIR_IMAGE_MAX_DIM, so a header may ask for a large (but bounded)
 * allocation. */
#include "fuzz.h"
#include "iir/image.h"
#include "image/image_internal.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    iir_image *img = (iir_image *)1; /* must be set to NULL on error */
    iir_error e;
    e.msg[0] = '\0';
    iir_status st = iir_image_read_pfm_memory(data, size, "fuzz.pfm", &img, &e);
    if (st != IIR_OK) {
        FUZZ_CHECK(img == NULL);
        FUZZ_CHECK(e.status == st && e.msg[0] != '\0');
        fuzz_note("error: %s", e.msg);
        return 0;
    }
    FUZZ_CHECK(img && img->width >= 1 && img->height >= 1);
    fuzz_note("image %dx%d", img->width, img->height);
    /* the pixel data follows the header, 4 bytes per channel */
    FUZZ_CHECK((size_t)img->width * (size_t)img->height * 4 <= size);
    iir_image_destroy(img);
    return 0;
}
