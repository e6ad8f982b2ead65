/* accelcal -- integer-only accelerometer-array core.  One include for all. */
#ifndef ACCELCAL_H
#define ACCELCAL_H

#define ACCELCAL_VERSION "0.1.0"

#include "ac_config.h"
#include "ac_status.h"
#include "ac_fixed.h"
#include "ac_xf.h"
#include "ac_trim.h"
#include "ac_resolve.h"
#include "ac_temp.h"
#include "ac_skew.h"
#include "ac_nonlin.h"
#include "ac_invert.h"
#include "ac_rate.h"
#include "ac_trig.h"
#include "ac_rest.h"
#include "ac_attitude.h"
#include "ac_displace.h"
#include "ac_omega.h"

#endif /* ACCELCAL_H */
