"""Calibration estimators: known poses, jig-free (unknown poses), lever arms, temperature.

Model (docs/data-contract.md, seed paper eqs. 16-19): at rest channel i reads

    m_pi = b_i + s_i . f_p (+ noise)                      pose p, specific force f_p

and with temperature ``b_i(T) = b_i + beta_i (T - T0)``,
``s_i(T) = s_i (1 + gamma_i (T - T0))``.  Every estimator works on pose means
(one row per static pose), so a recording of any length costs one vectorised
pass to reduce and a small solve afterwards.

Free parameters per channel (``method``):

``offset``  b_i only; s_i stays nominal (k_i u_i)            -- seed doc 2, 1-pose
``gain``    b_i and k_i with s_i = k_i u_i (nominal axis)      -- seed doc 2, 3-pose
``full``    b_i and the whole vector s_i                       -- seed paper, 6-pose, N-pose

Known poses (f_p given): per-channel weighted least squares, closed form.  A pose
set that cannot determine a parameter raises :class:`InputError` naming the
channel and the pose to add.

Jig accuracy (known poses): a real jig holds pose p not at the stated f_p but
rotated from it by a small error delta_p.  ``jig_accuracy_deg`` = theta states
the rms angle of that rotation (about a random axis; each axis component of
delta_p then has rms theta/sqrt(3)).  With theta > 0 the pose directions are
estimated jointly with every channel's parameters, as in the jig-free model
below, but each with its reference as a prior: per pose, the two tangent-plane
coordinates a_p of the estimated direction about the reference direction
(f_p = |f_ref,p| (d_p + T_p a_p)/|d_p + T_p a_p|, T_p an orthonormal basis
across d_p) enter as two extra residuals

    a_p / (theta / sqrt(3))

(the magnitude |f_ref,p| is kept).  One pose error then moves all of a pose's
channels together, as it does in the sensor, and the channels that see it
determine it: on the six poses +-x, +-y, +-z channel i's offset comes
essentially from the +-i pair (as in Ferraris's method) instead of absorbing
g sin(error) from the four cross poses, and on general pose sets (no pose along
most channel axes) the errors are at the bound for a jig of that accuracy
(tools/bench_calibration.py; on the six-pose set at 2 deg and more the offsets
are somewhat worse than the +-i pair mean: second-order terms from pose tilts
that only the priors set).  The priors fix the common rotation (no gauge
constraint: the result is in the jig's frame, known to about theta/sqrt(3 P)
per axis) and keep the model determined by every pose set the known-pose fit
accepts (the prior rows make the pose coordinates full rank; the channel
parameters need what they need with the poses fixed).  The
covariance is the inverse of J^T J over the reading and prior rows, chi^2 sums
both, and dof = P N - (channel parameters) as for fixed poses (2 rows and 2
parameters a pose).  As theta -> 0 the fit tends to the known-pose fit; theta =
0 is that fit exactly: ordinary weighted least squares, efficient (at the
Cramer-Rao bound) when the references are exact.  With theta = 0 stated and
chi^2/dof > JIG_HINT_CHI2 the fit reports the theta at which the prior model's
chi^2/dof is 1 (StaticFit.jig_hint_deg; the CLI warns with it).  Jig-free fits
ignore theta (they use no reference).

Jig accuracy estimated (the default of :func:`calibrate_recordings`, theta = "auto";
:mod:`.jig_estimate`): theta is the hyperparameter of the pose priors, estimated by
empirical Bayes: the restricted (REML) marginal likelihood of the pose means, with the
pose errors and the channel parameters integrated out (linearised about the fit with
exact references), maximised over theta with scipy.  A perfect jig is kept (theta = 0,
ordinary least squares) unless the likelihood-ratio test of theta = 0 (null: 1/2 chi2_0
+ 1/2 chi2_1, theta = 0 on the boundary) rejects it at 5 %; else the prior fit above runs
at theta-hat.  The calibration's ``extra["fit"]["jig_accuracy_estimate"]`` holds the
estimate, its 95 % profile-likelihood interval, the test's statistic and p-value.

Jig-free (f_p unknown, ``|f_p| = g``): one nonlinear least-squares problem over
the channel parameters and two tangent-plane angles per pose (``scipy.optimize.least_squares``
with an analytic Jacobian), started from an offset + gain fit.  It needs at
least 9 poses in general position for ``full`` (the readings fix the parameters
only up to an affine map of f, and |f| = g must rule it out; see _min_poses).
With ``full`` the data cannot tell a common rotation of all s_i and all f_p from
the truth, so the frame is fixed by the nominal geometry:

    GAUGE: the body frame is the one in which the orthogonal-Procrustes rotation
    from the nominal axes u_i to the estimated axis directions s_i/|s_i| is the
    identity, i.e. ``sum_i u_i x (s_i/|s_i|) = 0`` (3 equations).

The same rule holds for triads and arrays (one implementation): the estimated
axes are, as a set, rotated as little as possible from the nominal ones, and the
remaining misalignment is shared among the channels instead of being pinned on
channel 0 (imu_tk's upper-triangular choice is another valid gauge; results
differ from it by one rotation).  With ``gain`` or ``offset`` the axes are
nominal, which fixes the frame, and no gauge is needed.

Uncertainties: the covariance of the estimate is the inverse Fisher information
of the model (weights = 1/variance of each pose mean, the variance from the
pooled within-pose scatter of each channel; with a stated jig accuracy, plus the
prior rows), restricted to the gauge for jig-free ``full``.  When the fit is
worse than the noise (chi^2/dof > 1, e.g. pose errors of a jig), the covariance
is inflated by chi^2/dof (Birge ratio).

Temperature: first order about T0 = the mean pose temperature, fitted jointly with
the channel parameters (and the poses, jig-free) when the pose temperatures span
at least TEMP_MIN_SPAN_C.  Lever arms: from samples that rotate with reference f,
w and dw (rate table), per channel linear least squares for delta_r_i with the
static calibration held, reported per principal direction with its observability.

Static poses come from a recording's ``pose`` labels, or from
:func:`accelcal.readings.static.detect_static` (windowed std against the channel noise).
See :func:`calibrate_recordings` for the entry point the command line uses.

Modules: ``settings`` (constants), ``results`` (StaticFit, PositionFit), ``checks``
(shared checks of pose sets), ``problem`` (the static model as a least-squares
problem), ``static_model`` (the nonlinear fit by scipy.optimize.least_squares),
``known_poses`` (linear known-pose fits and the jig-accuracy joint fit), ``jig_estimate`` (the jig
accuracy estimated from the poses' scatter),
``lever_arms``, ``outliers`` (poses far off a fit, named with the fit without them), ``stated_poses``
(known poses whose readings contradict their stated f, refused before the fit),
``recordings`` (recordings in, a Calibration out).
"""
from ..readings.noise import estimate_noise
from ..readings.static import PoseSet, detect_static, pose_means, poses_from_recording
from .checks import jig_accuracy_rad, static_force
from .known_poses import calibrate_known_poses, fit_known_poses
from .jig_estimate import JigEstimate, estimate_jig_accuracy, fit_estimating_jig
from .lever_arms import calibrate_positions
from .problem import gauge_rotation
from .recordings import calibrate_recordings, to_calibration
from .results import PositionFit, StaticFit
from .settings import JIG_ACCURACY_AUTO, JIG_ACCURACY_DEG, JIGFREE_MODELS, METHODS, TEMP_MIN_SPAN_C
from .static_model import calibrate_jigfree, fit_static, fit_temperature

__all__ = [
    "METHODS", "JIGFREE_MODELS", "JIG_ACCURACY_AUTO", "JIG_ACCURACY_DEG", "TEMP_MIN_SPAN_C",
    "PoseSet", "StaticFit", "PositionFit", "JigEstimate", "estimate_jig_accuracy", "fit_estimating_jig",
    "detect_static", "estimate_noise", "pose_means", "poses_from_recording",
    "calibrate_known_poses", "calibrate_jigfree", "fit_known_poses", "fit_static", "fit_temperature",
    "calibrate_positions", "calibrate_recordings", "gauge_rotation", "jig_accuracy_rad", "static_force",
    "to_calibration",
]
