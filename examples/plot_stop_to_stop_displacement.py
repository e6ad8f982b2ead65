"""
Stop-to-stop displacement
=========================

A 3-axis sensor on a linear actuator: at rest, a 0.5 m stroke along x in 2 s, at rest
again. Integrating f twice turns any zero-point error into a position error that grows
with the square of time; here the sensor's x offset has moved by 0.05 m/s^2 (5 mg)
since it was calibrated. ``ac.displacement`` knows that the velocity is zero at each
rest: it finds the rests, and takes the zero-point error from the velocity left at the
stop, spread back over the stroke. ``axis="x"`` is the seed's 1-D case (f_x integrated,
nothing removed); without it the rests' gravity is removed in 3-D. The C core's streaming estimator
(``engine="fixed"``, ``ac_displace``) does the same sample by sample in firmware.
"""

import matplotlib.pyplot as plt
import numpy as np

import accelcal as ac

G = 9.80665
k = 16384 / G
tri = ac.Device(name="triad", sample_rate_hz=100.0, gravity_mps2=G, raw_min=-32768, raw_max=32767,
                positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, k),
                zero_counts=np.zeros(3), noise_mps2=0.005)
cal = ac.calibrate(tri, ac.simulate(tri, "static_poses", poses="6", seed=1))

# %%
# The stroke, with the zero-point error: x's offset 0.05 m/s^2 (82 counts) off the
# calibration's.
stroke = ac.simulate(tri, "linear_actuator", axis="x", distance_m=0.5, travel_s=2.0, rest_s=2.0, seed=2,
                     effects=[f"offset:db={0.05 * k:.3f},channel=0"])
s = np.clip((stroke.t - 2.0) / 2.0, 0.0, 1.0)
p_true = 0.5 * (10 * s ** 3 - 15 * s ** 4 + 6 * s ** 5)      # the minimum-jerk stroke

offline = ac.displacement(tri, cal, stroke, axis="x")                   # float reference, offline
fixed = ac.displacement(tri, cal, stroke, engine="fixed", axis="x")    # the C core, streaming
for name, out in (("float, offline", offline), ("C core, streaming", fixed)):
    print(f"{name:18s} travel {out['p_x'][-1]:.4f} m ({100 * (out['p_x'][-1] / 0.5 - 1):+.3f} %), "
          f"integrated twice, uncorrected {out['p_raw_x'][-1]:.4f} m ({100 * (out['p_raw_x'][-1] / 0.5 - 1):+.1f} %)")
for w in fixed.warnings:
    print("warning:", w)

# %%
fig, axs = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
axs[0].plot(stroke.t, p_true, "k", lw=2, label="true")
axs[0].plot(stroke.t, fixed["p_raw_x"], ":", label="integrated twice, uncorrected")
axs[0].plot(stroke.t, fixed["p_x"], label="C core, zero velocity at the rests")
axs[0].set(ylabel="p_x [m]")
axs[0].legend(loc="upper left")
axs[1].plot(stroke.t, 1000 * (offline["p_x"] - p_true), label="float, offline")
axs[1].plot(stroke.t, 1000 * (fixed["p_x"] - p_true), "--", label="C core, streaming")
rest = np.asarray(fixed["rest"]) > 0
axs[1].fill_between(stroke.t, 0, 1, where=rest, color="0.9", transform=axs[1].get_xaxis_transform(),
                    label="rest found")
axs[1].set(xlabel="t [s]", ylabel="p_x error [mm]")
axs[1].legend(loc="upper left")
fig.tight_layout()
