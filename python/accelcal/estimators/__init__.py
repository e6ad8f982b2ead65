"""Motion estimators: pendulum attitude from two triads (seed 3), stop-to-stop
displacement (seed 4) and angular rate from alpha with reset on rest (seed 1).

One module per estimator, each with three layers as everywhere in accelcal:

* **float core** (float64, the truth the C core is held to): the same algorithm as
  ``csrc/ac_attitude.c``, ``ac_displace.c``, ``ac_rest.c``, taking its constants as
  floats.  Fed the exact geometry it is the reference (``engine="float"``); fed the
  constants as the C structs store them, the same clipped integer inputs and the C
  decisions (gate, sign, rest) it is the **twin** the property tests compare the C code
  with, sample by sample, within the bounds stated in the headers.
* **fixed-point wrapper** through cffi (``*_fixed``): the C core on arrays.
* **recording form** (``*_from_recording``) returning :class:`Columns`; plots in
  :mod:`.plots`.

Modules: :mod:`.common` (Columns, input conventions), :mod:`.triad`, :mod:`.rest`,
:mod:`.trend` (the rests' trend test), :mod:`.attitude`, :mod:`.displacement` (streaming, the firmware's form),
:mod:`.displacement_host` (offline form, path correction, recordings), :mod:`.displacement_checks`
and :mod:`.motion_checks` (its warnings: of the rests, of the motions), :mod:`.rate`,
:mod:`.omega` (the array's own omega from the centripetal term, fused with the integrated
alpha; :mod:`.omega_fixed` its C core and float twin), :mod:`.plots`.  Q formats come from the compiled core (``native.FORMATS``).
Conventions follow docs/data-contract.md.
"""
from __future__ import annotations

from .attitude import (ANGLE_FRAC, ATT_GATED, ATT_NO_GRAVITY, ATT_SAT, ATT_SIGN_NEG, ATT_UNSETTLED, ATT_W2_NEG,
                       W2_FRAC, W_FRAC, AttitudeConsts, AttitudeParams, att_init_fixed, atan2_fixed, attitude_core,
                       attitude_fixed, attitude_float, attitude_from_recording, attitude_rate_bound, attitude_twin,
                       triad_geometry)
from .common import (CLIP, CLIP_LO, OMEGA_FRAC, OUT_FRAC, Columns, alpha_noise, clip_i16, dt_fixed, q_out,
                     resolve_array, uniform_dt)
from .displacement import (A_FRAC, DISP_BAD_REF, DISP_LONG, DISP_MOVING, DISP_NO_REF, DISP_NO_REST, DISP_OPEN,
                           DISP_REF_SET, DISP_REST, DISP_SAT, DISP_SEG_END, G_FRAC, GSUM_MAX, P_FRAC, ROT_FRAC,
                           V_FRAC, DisplaceParams, disp_cfg_fixed, displace_core, displace_error_bound,
                           displace_fixed, displace_stream, displace_twin, tilt_frame)
from .motion_checks import ZP_TURN_MPS2, turned_motions, zp_limit
from .displacement_host import displace_offline, displacement_from_recording, retro_correct
from .omega import (OMEGA_SOURCES, ArrayOmega, OmegaObservability, array_omega, choose_omega, omega_columns,
                    omega_crb, omega_from_recording, omega_ml, omega_observability)
from .omega_fixed import choose_omega_engine, omega_fixed_from_recording
from .plots import report_plots
from .rate import rate_from_recording, rate_rest_fixed, rate_rest_float
from .rest import (REST_AT_REST, REST_CLIP, REST_ENTER, REST_LEAVE, REST_QUIET, RestParams, RestState,
                   RestThresholds, default_rest_params, rest_cfg_fixed, rest_dated_back, rest_detect, rest_fixed,
                   rest_params_as_stored)
from .trend import rest_without_trend, trend_bound
from ..firmware.triad import (TriadTable, quantize_triad, triad_apply_fixed, triad_apply_float, triad_exact, triad_forces,
                    triad_matrix)

__all__ = [
    "Columns", "RestParams", "AttitudeParams", "DisplaceParams",
    "dt_fixed", "quantize_triad", "triad_apply_fixed", "triad_apply_float",
    "rest_detect", "rest_fixed", "rest_cfg_fixed", "rest_dated_back",
    "attitude_float", "attitude_fixed", "attitude_twin", "attitude_rate_bound",
    "tilt_frame", "displace_stream", "displace_fixed", "displace_twin", "displace_offline",
    "displace_error_bound", "rate_rest_float", "rate_rest_fixed",
    "attitude_from_recording", "displacement_from_recording", "rate_from_recording",
    "report_plots", "OMEGA_SOURCES", "ArrayOmega", "OmegaObservability", "array_omega", "choose_omega",
    "omega_columns", "omega_crb", "omega_from_recording", "omega_ml", "omega_observability",
    "choose_omega_engine", "omega_fixed_from_recording",
]
