/* isa.h -- the instruction sets the shading kernels are built for, and which one this machine
 * runs: the renderer's per-pixel loops exist once per set (scalar C, the reference the others are
 * tested against; SSE2, every x86-64; AVX2 with FMA and F16C) and the widest one the CPU supports
 * is chosen at run time, so one binary runs on any x86-64 machine. IIR_ISA in the environment
 * (scalar, sse2, avx2) caps the choice, for measuring one against another. */
#ifndef IIR_ISA_H
#define IIR_ISA_H

#include <stdbool.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum iir_isa { IIR_ISA_SCALAR, IIR_ISA_SSE2, IIR_ISA_AVX2, IIR_ISA_COUNT } iir_isa;

/* Whether this build has kernels for isa and this CPU can run them. Scalar always can. */
bool iir_isa_supported(iir_isa isa);
/* The widest supported set, capped by IIR_ISA when it names one (an unknown or unsupported name
 * is ignored, with a warning on stderr the first time). */
iir_isa iir_isa_default(void);
/* "scalar", "sse2", "avx2". */
const char *iir_isa_name(iir_isa isa);
/* The set named s, or IIR_ISA_COUNT when s names none. */
iir_isa iir_isa_parse(const char *s);

#ifdef __cplusplus
}
#endif
#endif
