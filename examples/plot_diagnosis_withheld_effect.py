"""
The diagnosis: an effect the model leaves out
=============================================

The calibration's model holds offsets, sensitivity vectors and positions; a real sensor
can do more. Here the seed's 6-channel array is read by a multiplexed ADC: channel i is
sampled i x 0.4 ms after channel 0 (a ``time_skew``, which the model leaves out). It is
calibrated on a jig, where nothing moves and the skew cannot show, then recorded on a
rate table. ``ac.diagnose`` compares the recordings with the model's prediction, finds
where the gap lies (which channels, which motions), tries each effect of its table, and
names the one that explains the gap, with its fitted parameters and how far it shrinks
the gap. The report (``accelcal diagnose --report DIR``) draws its figures.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt

import accelcal as ac
from accelcal.report import write_report

dev = ac.default_device()
skew = "time_skew:tau=0.0004,sequential=1"
poses = ac.simulate(dev, "static_poses", poses="24", seed=1, effects=[skew])
cal = ac.calibrate(dev, poses)
motion = ac.simulate(dev, "rate_table", axis="z", freq_hz=2.0, amplitude_deg=30.0, seed=2, effects=[skew])

# %%
# Diagnose
# --------
result = ac.diagnose(dev, cal, [poses, motion])
model = result["model"]
print(f"verdict: {result['verdict']}; model {model['effects']}, held-out RMS "
      f"{model['heldout_rms_before']:.3f} -> {model['heldout_rms_after']:.3f} counts (shrink {model['shrink']:.1%})")

# %%
# The skews fitted against the true ones. The tangential channels (0, 2, 4) feel the
# yaw and get their skews back; the z channels (1, 3, 5) feel nothing of a rotation
# about z, so their skews stay undetermined: the diagnosis says so with their sigmas.
tau = model["params"]["time_skew"]["tau"]
sigma = model["params_sigma"]["time_skew"]["tau"]
for i, (t, s) in enumerate(zip(tau, sigma)):
    print(f"channel {i}: tau {1e3 * t:+9.3f} +- {1e3 * s:7.3f} ms   (true {0.4 * i:.1f} ms)")

# %%
# The report's figures
# --------------------
# ``write_report`` writes what ``accelcal diagnose --report DIR`` writes: the residual over
# time, its breakdown by channel and recording, the candidates' shrink, and summary.md.
out = Path(tempfile.mkdtemp(prefix="accelcal-diag-"))
written = write_report(result, out)
for path in written:
    if path.endswith(".png"):
        img = plt.imread(path)
        fig, ax = plt.subplots(figsize=(img.shape[1] / 100, img.shape[0] / 100))
        ax.imshow(img)
        ax.set_axis_off()
        ax.set_title(Path(path).name, fontsize=9)
        fig.tight_layout()
print((out / "summary.md").read_text())
