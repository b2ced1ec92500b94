/* isa.c -- which instruction set the shading kernels run with: what the build has, what the CPU
 * supports (GCC's __builtin_cpu_supports) and the IIR_ISA cap (isa.h). */
#include "iir/isa.h"

#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const names[IIR_ISA_COUNT] = {"scalar", "sse2", "avx2"};

bool iir_isa_supported(iir_isa isa)
{
    switch (isa) {
    case IIR_ISA_SCALAR:
        return true;
#if defined(__x86_64__)
    case IIR_ISA_SSE2:
        return true; /* part of x86-64 */
    case IIR_ISA_AVX2:
        return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
               __builtin_cpu_supports("f16c");
#endif
    default:
        return false;
    }
}

const char *iir_isa_name(iir_isa isa)
{
    return isa >= 0 && isa < IIR_ISA_COUNT ? names[isa] : "unknown";
}

iir_isa iir_isa_parse(const char *s)
{
    for (int i = 0; s && i < IIR_ISA_COUNT; i++)
        if (!strcmp(s, names[i])) return (iir_isa)i;
    return IIR_ISA_COUNT;
}

iir_isa iir_isa_default(void)
{
    static atomic_bool warned;
    iir_isa best = IIR_ISA_SCALAR;
    for (int i = 0; i < IIR_ISA_COUNT; i++)
        if (iir_isa_supported((iir_isa)i)) best = (iir_isa)i;
    const char *env = getenv("IIR_ISA");
    if (!env || !*env) return best;
    iir_isa cap = iir_isa_parse(env);
    if (cap != IIR_ISA_COUNT && iir_isa_supported(cap)) return cap < best ? cap : best;
    if (!atomic_exchange(&warned, true))
        fprintf(stderr, "iir: IIR_ISA=%s is not one of this machine's (scalar, sse2%s); using %s\n",
                env, best >= IIR_ISA_AVX2 ? ", avx2" : "", names[best]);
    return best;
}
