"""
The seed's 6-channel array: calibrate, emit the header, resolve with the C core
===============================================================================

The built-in default device is the seed paper's prototype: three dual-axis chips
(ADXL202E) on a circle of r = 60 mm, six single-axis channels from which f (specific
force, m/s^2) and alpha (angular acceleration, rad/s^2) are resolved. This example

1. draws a "true" calibration unlike the datasheet's (gains, axes and offsets off, as
   the seed's Table 1 found them),
2. simulates 24 jig poses with it and calibrates (method ``full``: known poses),
3. emits the C header for firmware,
4. simulates the seed's 2 Hz yaw on a rate table and resolves it with the C core
   (``engine="fixed"``, exactly the header's integer tables) and with the float64
   reference, against the simulation's truth.

The same steps on the command line: ``accelcal demo``.
"""

import matplotlib.pyplot as plt
import numpy as np

import accelcal as ac

dev = ac.default_device()
print(dev.name, dev.n_channels, "channels at", dev.sample_rate_hz, "Hz")

# %%
# A "true" calibration
# --------------------
# Gains -0.7 ... +3.6 %, each sensitive axis tilted by up to 1.75 %, offsets up to
# +-28 % of g: the scatter the seed's Table 1 reports for its chips.
rng = np.random.default_rng(7)
nominal = ac.Calibration.nominal(dev)
k = np.linalg.norm(nominal.sensitivity, axis=1)
axes = nominal.sensitivity / k[:, None] + rng.uniform(-0.0175, 0.0175, (6, 3))
axes /= np.linalg.norm(axes, axis=1, keepdims=True)
truth = ac.Calibration(device=dev.name, method="truth",
                       offsets=nominal.offsets + rng.uniform(-0.28, 0.25, 6) * dev.gravity_mps2 * k,
                       sensitivity=(k * (1 + rng.uniform(-0.0069, 0.0358, 6)))[:, None] * axes)

# %%
# Calibrate from 24 jig poses
# ---------------------------
poses = ac.simulate(dev, "static_poses", poses="24", seed=1, calibration=truth)
cal = ac.calibrate(dev, poses)
fit = cal.extra["fit"]
print(f"method {cal.method}, chi2/dof {fit['chi2'] / fit['dof']:.3f}")

offset_err = cal.offsets - truth.offsets
gain_err = 100 * (np.linalg.norm(cal.sensitivity, axis=1) / np.linalg.norm(truth.sensitivity, axis=1) - 1)
nominal_gain_err = 100 * (k / np.linalg.norm(truth.sensitivity, axis=1) - 1)

fig, (a0, a1) = plt.subplots(1, 2, figsize=(9, 3.2))
ch = np.arange(6)
a0.bar(ch, offset_err, yerr=cal.offset_sigma, capsize=3)
a0.set(xlabel="channel", ylabel="offset error [counts]", title="calibrated offset - true offset")
a1.bar(ch - 0.2, nominal_gain_err, width=0.4, label="datasheet")
a1.bar(ch + 0.2, gain_err, width=0.4, label="calibrated")
a1.set(xlabel="channel", ylabel="gain error [%]", title="gain error against the truth")
a1.legend()
fig.tight_layout()

# %%
# The firmware header
# -------------------
# ``ac.header`` writes the calibration as the C core's fixed-point tables. Its opening
# comment states the input the tables expect and the error bound against the float
# reference.
text = ac.header(dev, cal)
print("\n".join(text.splitlines()[:40]))

# %%
# Resolve a motion with the C core and the float reference
# --------------------------------------------------------
# The seed's test motion: a 2 Hz yaw of +-30 deg about body z on a rate table. The C
# core is given the reference angular rate for its centripetal term (``omega="auto"``
# takes the recording's w columns).
motion = ac.simulate(dev, "rate_table", axis="z", freq_hz=2.0, amplitude_deg=30.0, seed=2, calibration=truth)
fixed = ac.resolve(dev, cal, motion, engine="fixed")
flt = ac.resolve(dev, cal, motion, engine="float")
raw_nominal = ac.resolve(dev, nominal, motion, engine="float")

lsb = 2.0 ** -10                                  # the outputs' Q21.10 step
print(f"C core vs float reference: max {np.abs(fixed.f - flt.f).max() / lsb:.2f} LSB (f), "
      f"{np.abs(fixed.alpha - flt.alpha).max() / lsb:.2f} LSB (alpha)")
for name, r in (("datasheet", raw_nominal), ("calibrated, float", flt), ("calibrated, C core", fixed)):
    print(f"{name:20s} f rms error {np.sqrt(np.mean((r.f - motion.f) ** 2)):.4f} m/s^2, "
          f"alpha_z rms error {np.sqrt(np.mean((r.alpha[:, 2] - motion.dw[:, 2]) ** 2)):.3f} rad/s^2")

sl = slice(0, int(2 * dev.sample_rate_hz))        # the first two seconds
fig, axs = plt.subplots(3, 1, figsize=(9, 7), sharex=True)
axs[0].plot(motion.t[sl], motion.dw[sl, 2], "k", lw=2, label="true")
axs[0].plot(motion.t[sl], fixed.alpha[sl, 2], label="C core")
axs[0].plot(motion.t[sl], raw_nominal.alpha[sl, 2], ":", label="datasheet values")
axs[0].set(ylabel="alpha_z [rad/s^2]")
axs[0].legend(loc="upper right")
axs[1].plot(motion.t[sl], motion.f[sl, 0], "k", lw=2, label="true")
axs[1].plot(motion.t[sl], fixed.f[sl, 0], label="C core")
axs[1].plot(motion.t[sl], raw_nominal.f[sl, 0], ":", label="datasheet values")
axs[1].set(ylabel="f_x [m/s^2]")
axs[2].plot(motion.t[sl], (fixed.f[sl] - flt.f[sl]) / lsb, ".", ms=2)
axs[2].set(xlabel="t [s]", ylabel="C core - float [LSB of f]")
fig.tight_layout()
