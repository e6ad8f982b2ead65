/*
 * accelcal -- status codes.  Every function returns one.
 *
 * Zero is success, a positive value is success with a warning (the outputs
 * are valid, but at least one was clipped to its range), a negative value is
 * an error (the outputs were not written).
 */
#ifndef AC_STATUS_H
#define AC_STATUS_H

typedef enum ac_status {
    AC_OK = 0,
    AC_SATURATED = 1,        /* an output or intermediate hit its limit and was clipped */
    AC_ERR_NULL = -1,        /* a required pointer was NULL */
    AC_ERR_SIZE = -2,        /* channel or sample count out of range */
    AC_ERR_SINGULAR = -3,    /* geometry does not determine f and alpha */
    AC_ERR_ILL_COND = -4,    /* geometry too ill-conditioned for a trustworthy inverse */
    AC_ERR_RANGE = -5,       /* a parameter is out of its representable range */
    AC_ERR_FORMAT = -6       /* a table is inconsistent (e.g. a shift out of range) */
} ac_status;

#endif /* AC_STATUS_H */
