/*
 * accelcal -- status codes.  Every function returns one.
 *
 * Zero is success, a positive value is success with warnings (the outputs
 * were written; its bits say what to distrust: AC_SATURATED, AC_AT_RAIL, or
 * both), a negative value is an error (the outputs were not written).
 */
#ifndef AC_STATUS_H
#define AC_STATUS_H

typedef enum ac_status {
    AC_OK = 0,
    AC_SATURATED = 1,        /* an output or intermediate hit its limit and was clipped */
    AC_AT_RAIL = 2,          /* a raw reading sat at its converter's rail (raw_min or raw_max):
                              * the outputs are computed, but from a reading the chip clipped,
                              * so they are not a measurement (ac_trim_rails, ac_trim_rails_s16,
                              * ac_process, ac_triad_apply; rails with raw_min < raw_max only) */
    AC_AT_RAIL_SATURATED = 3, /* both of the above */
    AC_ERR_NULL = -1,        /* a required pointer was NULL */
    AC_ERR_SIZE = -2,        /* channel or sample count out of range */
    AC_ERR_SINGULAR = -3,    /* geometry does not determine f and alpha */
    AC_ERR_ILL_COND = -4,    /* geometry too ill-conditioned for a trustworthy inverse */
    AC_ERR_RANGE = -5,       /* a parameter is out of its representable range */
    AC_ERR_FORMAT = -6       /* a table is inconsistent (e.g. a shift out of range) */
} ac_status;

#endif /* AC_STATUS_H */
