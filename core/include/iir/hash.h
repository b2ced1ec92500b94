/* hash.h -- FNV-1a 64 over bytes: the content keys of caches and logs (a light's, a material's, a
 * scene's, a form-factor file's), built field by field so padding never enters a key. */
#ifndef IIR_HASH_H
#define IIR_HASH_H

#include <stddef.h>
#include <stdint.h>

#define IIR_HASH_BASIS 0xcbf29ce484222325ull

static inline uint64_t iir_hash_bytes(uint64_t h, const void *data, size_t n)
{
    const unsigned char *p = data;
    for (size_t i = 0; i < n; i++) h = (h ^ p[i]) * 0x100000001b3ull;
    return h;
}

/* h extended by the bytes of lvalue x (a scalar, a vector of floats, an array: no padding). */
#define IIR_HASH(h, x) iir_hash_bytes((h), &(x), sizeof(x))

#endif
