/* half.h -- IEEE 754 half-precision floats (binary16) for data read far more often than written:
 * the VPL shadow maps' depths (shadowmap.h). Conversion to float is exact; from float rounds to
 * the nearest (ties to even), as F16C's vcvtps2ph and vcvtph2ps do, so a map read by a scalar
 * loop and by a vector kernel gives the same values. Only non-negative numbers and +infinity
 * are needed and handled (depths). */
#ifndef IIR_HALF_H
#define IIR_HALF_H

#include <stdint.h>

#include "iir/vecmath.h"

#define IIR_HALF_INF 0x7c00u

/* f >= 0 (or +infinity; NaN gives +infinity) to the nearest half; 65520 and beyond round to
 * +infinity, below 2^-24 to 0. */
static inline uint16_t iir_half_from_float(float f)
{
    uint32_t x = iir_float_bits(f) & 0x7fffffffu;
    if (x >= 0x477ff000u) return IIR_HALF_INF; /* >= 65520, +infinity, NaN */
    if (x < 0x38800000u) {                     /* below 2^-14: a subnormal half (or 0) */
        float m = iir_bits_float(x) * 0x1p24f; /* the subnormal's mantissa, exact in a float */
        uint32_t k = (uint32_t)m;
        float rest = m - (float)k;
        return (uint16_t)(k + (rest > 0.5f || (rest == 0.5f && (k & 1u))));
    }
    x += 0xc8000fffu + ((x >> 13) & 1u); /* exponent -112, round to nearest even */
    return (uint16_t)(x >> 13);
}

/* h (non-negative) as a float, exactly: its bits moved into a float's and scaled by 2^112, which
 * is exact for normal and subnormal halves alike; the maximum exponent is +infinity. */
static inline float iir_half_to_float(uint16_t h)
{
    if ((h & IIR_HALF_INF) == IIR_HALF_INF) return iir_bits_float(0x7f800000u);
    return iir_bits_float((uint32_t)(h & 0x7fffu) << 13) * 0x1p112f;
}

#endif
