/* rng.h -- deterministic random numbers: PCG32 streams and a counter hash to seed them per pixel
 * and sample, so images depend only on the seed (not on thread count or tile order); plus the
 * radical inverse for Halton/Hammersley sets. Inline, no state beyond the iir_rng value. */
#ifndef IIR_RNG_H
#define IIR_RNG_H

#include <stdint.h>

#include "iir/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct iir_rng {
    uint64_t state, inc;
} iir_rng;

/* 64-bit finaliser (splitmix64): a good hash of a counter. */
static inline uint64_t iir_mix64(uint64_t z)
{
    z += 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static inline uint64_t iir_hash3(uint64_t a, uint64_t b, uint64_t c)
{
    return iir_mix64(a ^ iir_mix64(b ^ iir_mix64(c)));
}

static inline uint32_t iir_rng_u32(iir_rng *r)
{
    uint64_t old = r->state;
    r->state = old * 6364136223846793005ull + r->inc;
    uint32_t xorshifted = (uint32_t)(((old >> 18u) ^ old) >> 27u);
    uint32_t rot = (uint32_t)(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((-rot) & 31));
}

/* A stream determined by (seed, stream). */
static inline iir_rng iir_rng_make(uint64_t seed, uint64_t stream)
{
    iir_rng r = {0u, (iir_mix64(stream) << 1u) | 1u};
    iir_rng_u32(&r);
    r.state += iir_mix64(seed);
    iir_rng_u32(&r);
    return r;
}

/* Uniform in [0, 1). */
static inline float iir_rng_uniform(iir_rng *r)
{
    return (float)(iir_rng_u32(r) >> 8) * 0x1p-24f;
}

static inline iir_vec2 iir_rng_uniform2(iir_rng *r)
{
    float a = iir_rng_uniform(r);
    return iir_v2(a, iir_rng_uniform(r));
}

/* Radical inverse of i in the given prime base (Halton component), in [0, 1). */
static inline float iir_radical_inverse(uint32_t base, uint64_t i)
{
    double inv = 1.0 / base, f = inv, v = 0.0;
    for (; i > 0; i /= base, f *= inv) v += (double)(i % base) * f;
    return (float)(v < 1.0 ? v : 0x1.fffffep-1);
}

#ifdef __cplusplus
}
#endif
#endif
