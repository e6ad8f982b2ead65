/* accelcal -- one external copy of the internal 64-bit shifts, for compilers that
 * do not inline them (see ac_internal.h, ac_ops64.c). */
#include "ac_internal.h"

#if !AC_INLINE_HELPERS
#define AC_HELPER
#define AC_U64_SHIFTS_ONLY
#include "ac_u64_impl.h"
#else
/* ISO C forbids an empty translation unit */
typedef int ac_ops64_shift_inlined;
#endif
