"""
A 3-axis MEMS chip from a logger's file: convert, calibrate, header, firmware
=============================================================================

A 3-axis chip (an MPU-6050 class part: signed 16-bit counts, +-2 g, 100 Hz) read by
a microcontroller that prints ``millis()`` and the six raw registers a line (a header
line names the columns). The
chip's zero-g offsets and sensitivities are off by what such parts ship with; the
sensor was turned by hand through 16 orientations and held still in each, with no
jig. This example

1. writes such a log (simulated here, so that the truth is known),
2. converts it to the project's recording and a nominal device (``ac.convert``, as
   ``accelcal convert LOG --full-scale 2``),
3. calibrates it jig-free (the still poses, ``|f| = g``),
4. emits the firmware header and shows how firmware uses it.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import accelcal as ac

work = Path(tempfile.mkdtemp(prefix="accelcal-mems-"))

# %%
# The logger's file
# -----------------
# The chip as it is: offsets of +700, -360 and -1,800 counts (43, 22 and 110 mg),
# gains -0.3, +0.2 and +2.3 % off 16,384 counts per g, axes a few mrad off.
G = 9.80665
k = 16384 / G                                     # counts per m/s^2 at +-2 g
chip = ac.Device(name="mpu6050-like", sample_rate_hz=100.0, gravity_mps2=G, raw_min=-32768, raw_max=32767,
                 positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, k),
                 zero_counts=np.zeros(3), noise_mps2=0.004)
axes = np.eye(3) + np.array([[0, 0.004, -0.002], [0.003, 0, 0.001], [-0.002, 0.005, 0]])
truth = ac.Calibration(device=chip.name, method="truth", offsets=[700.0, -360.0, -1800.0],
                       sensitivity=(k * np.array([0.997, 1.002, 1.023]))[:, None] * axes)
session = ac.simulate(chip, "handheld", n_poses=16, hold_s=3.0, move_s=1.5, initial_rest_s=5.0,
                      seed=4, calibration=truth)

rng = np.random.default_rng(0)
log = work / "LOG00042.CSV"
with open(log, "w") as out:
    out.write("timestamp_ms,ax,ay,az,gx,gy,gz\n")
    for t, (ax, ay, az) in zip(session.t, session.raw):
        gx, gy, gz = rng.integers(-40, 40, 3)    # the gyroscope's registers, which accelcal leaves out
        out.write(f"{round(1000 * t)},{ax},{ay},{az},{gx},{gy},{gz}\n")
print(log.read_text()[:200])

# %%
# Convert
# -------
# The converter finds the time column (``timestamp_ms``: milliseconds, from its name) and
# the accelerometer's columns, drops the gyroscope's, and makes a nominal device:
# signed counts, 16,384 per g from the stated full scale.
conv = ac.convert(log, full_scale_g=2)
for note in conv.notes + conv.device_notes:
    print("note:", note)
dev, rec = conv.device, conv.recording
print(f"format {conv.format}: {len(rec.t)} rows at {dev.sample_rate_hz:.2f} Hz, "
      f"raw {dev.raw_min}..{dev.raw_max}, {dev.counts_per_mps2[0]:.1f} counts per m/s^2")

# %%
# Calibrate without a jig
# -----------------------
cal = ac.calibrate(dev, rec)
fit = cal.extra["fit"]
print(f"method {cal.method}, {len(cal.poses_used or [])} poses, chi2/dof {fit['chi2'] / fit['dof']:.2f}")
print("offsets [counts]:", np.round(cal.offsets, 1), "true:", truth.offsets)
print("gains [%]:", np.round(100 * (np.linalg.norm(cal.sensitivity, axis=1) / k - 1), 3))

# %%
# ``|f|`` over the recording with the datasheet's scale and with the calibration: at rest
# it should read g.
nominal = ac.Calibration.nominal(dev)
f_nom = ac.resolve(dev, nominal, rec).f
f_cal = ac.resolve(dev, cal, rec, engine="fixed").f          # the C core, as the firmware will
fig, ax = plt.subplots(figsize=(9, 3.5))
ax.plot(rec.t, np.linalg.norm(f_nom, axis=1), lw=0.8, label="datasheet values")
ax.plot(rec.t, np.linalg.norm(f_cal, axis=1), lw=0.8, label="calibrated (C core)")
ax.axhline(G, color="k", ls=":", lw=1)
ax.set(xlabel="t [s]", ylabel="|f| [m/s^2]", ylim=(G - 1.2, G + 1.2),
       title="|f| on the hand-held session: the still poses read g after calibration")
ax.legend(loc="lower right")
fig.tight_layout()

# %%
# The pose means' ``|f| - g``, pose by pose (the poses as the simulation held them; the
# converted file has no labels, the calibration found the still stretches itself).
labels = np.unique(session.pose[session.pose >= 0])
err_nom = [np.linalg.norm(f_nom[session.pose == p].mean(axis=0)) - G for p in labels]
err_cal = [np.linalg.norm(f_cal[session.pose == p].mean(axis=0)) - G for p in labels]
fig, ax = plt.subplots(figsize=(9, 3))
ax.bar(labels - 0.2, 1000 * np.array(err_nom) / G, width=0.4, label="datasheet values")
ax.bar(labels + 0.2, 1000 * np.array(err_cal) / G, width=0.4, label="calibrated (C core)")
ax.set(xlabel="pose", ylabel="|mean f| - g [mg]")
ax.legend()
fig.tight_layout()
print(f"|mean f| - g over the poses, rms: datasheet {1000 * np.sqrt(np.mean(np.square(err_nom))) / G:.1f} mg, "
      f"calibrated {1000 * np.sqrt(np.mean(np.square(err_cal))) / G:.2f} mg")

# %%
# The firmware header
# -------------------
# A 3-axis chip gets the triad table: f = S^-1 (raw - b) in Q21.10 m/s^2. The chip's
# output is signed, so the table's trims are ``int16_t`` and the pre-trim is
# ``ac_trim_rails_s16`` (its status flags a reading at the rails: the chip clipped).
text = ac.header(dev, cal, output=work / "accel_cal.h")
lines = text.splitlines()
print("\n".join(lines[:30]))
print("...")
print("\n".join(lines[lines.index("#ifdef AC_CAL_IMPLEMENTATION"):]))

# %%
# In the firmware
# ---------------
# Link the core (``csrc/*.c``, ``include/`` on the include path; see the C core's page)
# and call it per sample:
#
# .. code-block:: c
#
#     #define AC_CAL_IMPLEMENTATION          /* in exactly one .c file */
#     #include "accel_cal.h"                 /* written by accelcal header */
#
#     void on_sample(const int16_t reg[3])   /* ACCEL_XOUT..ACCEL_ZOUT as read */
#     {
#         int16_t x[3];
#         int32_t f[3];                      /* m/s^2, Q21.10: f[i] / 1024.0 */
#         ac_status st = ac_trim_rails_s16(reg, AC_CAL_TRIM, 3, AC_CAL_RAW_MIN, AC_CAL_RAW_MAX, x);
#         if (st >= 0)
#             st |= ac_triad_resolve(&AC_CAL_TRIAD, x, f);
#         if (st < 0)            { /* error: f not written */ }
#         else if (st & AC_AT_RAIL) { /* the chip clipped: f is no measurement */ }
#     }
#
# ``accelcal resolve --engine fixed`` (``ac.resolve(..., engine="fixed")`` above) runs
# exactly this arithmetic on the host, bit for bit.
