/* accelcal -- one external copy of the internal helpers, for compilers that do
 * not inline them (see ac_internal.h). */
#include "ac_internal.h"

#if !AC_INLINE_HELPERS
#define AC_HELPER
#include "ac_ops_impl.h"
#else
/* ISO C forbids an empty translation unit */
typedef int ac_ops_inlined;
#endif
