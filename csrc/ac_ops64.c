/* accelcal -- one external copy of the internal 64-bit arithmetic helpers
 * (multiply, add, subtract, compare), for compilers that do not inline them (see
 * ac_internal.h); the shifts are ac_ops64_shift.c. */
#include "ac_internal.h"

#if !AC_INLINE_HELPERS
#define AC_HELPER
#define AC_U64_ARITH_ONLY
#include "ac_u64_impl.h"
#else
/* ISO C forbids an empty translation unit */
typedef int ac_ops64_inlined;
#endif
