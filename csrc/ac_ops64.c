/* accelcal -- one external copy of the internal 64-bit helpers, for compilers
 * that do not inline them (see ac_internal.h). */
#include "ac_internal.h"

#if !AC_INLINE_HELPERS
#define AC_HELPER
#include "ac_u64_impl.h"
#else
/* ISO C forbids an empty translation unit */
typedef int ac_ops64_inlined;
#endif
