"""
The two-triad pendulum: attitude from accelerometers alone
==========================================================

Two 3-axis accelerometers on a pendulum's arm, at r1 = 0.1 m and r2 = 0.3 m from the
pivot (the body origin), the arm swinging about body y. The difference of the two
triads' readings is the rotation's share (angular acceleration and centripetal term),
which takes it out of f: what is left is gravity, whose direction is the attitude. The
square root of the centripetal term gives the rate, the tangential term its derivative
(the seed paper's eqs. 2-3). ``ac.attitude`` does this with the float reference or
with the C core (``engine="fixed"``: ``ac_attitude``).
"""

import matplotlib.pyplot as plt
import numpy as np

import accelcal as ac

G = 9.80665
pend = ac.Device(name="pendulum", sample_rate_hz=100.0, gravity_mps2=G, raw_min=0, raw_max=65535,
                 positions=np.array([[0.1, 0, 0]] * 3 + [[0.3, 0, 0]] * 3), axes=np.vstack([np.eye(3)] * 2),
                 counts_per_mps2=np.full(6, 16384 / G), zero_counts=np.full(6, 32768.0), noise_mps2=0.005)

# %%
# A swing of +-40 deg at 0.5 Hz for 20 s, and the two triads calibrated on a jig
# (the same 24 poses for both: the pendulum's arm clamped in each).
cal = ac.calibrate(pend, ac.simulate(pend, "static_poses", poses="24", seed=1))
swing = ac.simulate(pend, "pendulum", amplitude_deg=40.0, freq_hz=0.5, duration_s=20.0, seed=2)
theta_true = np.radians(40.0) * np.cos(2 * np.pi * 0.5 * swing.t)   # the motion's attitude about y

flt = ac.attitude(pend, cal, swing, engine="float")
fixed = ac.attitude(pend, cal, swing, engine="fixed")
err_flt = np.degrees(flt["theta_rad"] - theta_true)
err_fix = np.degrees(fixed["theta_rad"] - theta_true)
print(f"attitude rms error: float {np.sqrt(np.mean(err_flt ** 2)):.3f} deg, "
      f"C core {np.sqrt(np.mean(err_fix ** 2)):.3f} deg (max {np.abs(err_fix).max():.2f} deg)")
w_err = fixed["w_y"] - swing.w[:, 1]
print(f"rate w_y rms error, C core: {np.sqrt(np.mean(w_err ** 2)):.4f} rad/s "
      f"(peak rate {np.abs(swing.w[:, 1]).max():.2f} rad/s); "
      f"{100 * np.mean(fixed['gated'] > 0):.0f} % of samples gated (rate too small to measure: integrated)")

# %%
fig, axs = plt.subplots(3, 1, figsize=(9, 7.5), sharex=True)
sl = swing.t <= 6.0
axs[0].plot(swing.t[sl], np.degrees(theta_true[sl]), "k", lw=2, label="true")
axs[0].plot(swing.t[sl], np.degrees(fixed["theta_rad"][sl]), label="C core")
axs[0].set(ylabel="theta [deg]")
axs[0].legend(loc="upper right")
axs[1].plot(swing.t[sl], swing.w[sl, 1], "k", lw=2, label="true")
axs[1].plot(swing.t[sl], fixed["w_y"][sl], label="C core")
axs[1].set(ylabel="w_y [rad/s]")
axs[2].plot(swing.t[sl], err_flt[sl], label="float reference")
axs[2].plot(swing.t[sl], err_fix[sl], "--", label="C core")
axs[2].set(xlabel="t [s]", ylabel="attitude error [deg]")
axs[2].legend(loc="upper right")
fig.tight_layout()
