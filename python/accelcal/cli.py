"""The ``accelcal`` command (forms fixed by shared/spec/data-contract.md).

Every subcommand exits 0 on success; on bad input it prints one line to stderr
(no traceback) and exits 2, leaving no partial output file (all outputs are
written through errors.atomic_write).
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from .errors import AccelcalError, atomic_write
from .estimators import attitude_from_recording, displacement_from_recording, rate_from_recording, report_plots
from .recording import read_recording, write_columns_csv

EXIT_INPUT = 2
EXIT_INTERNAL = 3


def _load_device(path):
    from .device import default_device, load_device
    return default_device() if path in (None, "default") else load_device(path)


def _load_cal(path, device):
    from .calibration import load_calibration
    return load_calibration(path, device)


def _write_csv(path, header: list[str], columns: list[np.ndarray], comments: dict):
    write_columns_csv(path, dict(zip(header, columns)), comments)


def _progress(desc: str, total: int | None = None, unit: str = " steps"):
    """A progress bar on stderr for work that takes seconds on long recordings.  Off when
    stderr is not a terminal (tqdm's disable=None): pipes, logs and scripts see only the
    one-line messages."""
    from tqdm import tqdm
    return tqdm(desc=desc, total=total, unit=unit, file=sys.stderr, disable=None, leave=False,
                dynamic_ncols=True)


# ---- subcommands -------------------------------------------------------------

def cmd_resolve(a):
    from .recording import read_recording
    from .resolve import resolve_recording
    dev = _load_device(a.device)
    cal = _load_cal(a.calibration, dev)
    rec = read_recording(a.recording, dev.n_channels)
    f, al, flags = resolve_recording(dev, cal, rec, a.engine, a.omega)
    comments = {"engine": a.engine, "device": dev.name}
    if flags is not None and flags.any():
        print(f"accelcal resolve: warning: {int(np.count_nonzero(flags))} samples saturated in the "
              "fixed-point core (see column saturated)", file=sys.stderr)
    cols = [rec.t, f[:, 0], f[:, 1], f[:, 2], al[:, 0], al[:, 1], al[:, 2]]
    header = ["t", "f_x", "f_y", "f_z", "dw_x", "dw_y", "dw_z"]
    if flags is not None:
        cols.append(flags.astype(float))
        header.append("saturated")
    _write_csv(a.output, header, cols, comments)
    return 0


def cmd_header(a):
    from .header import render_header
    from .quantize import quantize_calibration
    dev = _load_device(a.device)
    cal = _load_cal(a.calibration, dev)
    t = quantize_calibration(dev, cal)
    text = render_header(t, prefix=a.prefix, calibration_method=cal.method,
                         temp_ref_c=getattr(cal, "temp_ref_c", None),
                         offset_tc=getattr(cal, "offset_tc", None), gain_tc=getattr(cal, "gain_tc", None))
    atomic_write(a.output, lambda f: f.write(text))
    return 0


def cmd_simulate(a):
    from .effects import parse_effect_spec
    from .recording import write_recording
    from .simulate import simulate
    dev = _load_device(a.device)
    effects = [parse_effect_spec(s) for s in a.effect]
    params = {}
    for kv in a.param:
        if "=" not in kv:
            raise AccelcalError(f"--param {kv!r}: expected NAME=VALUE")
        k, v = kv.split("=", 1)
        try:
            params[k] = json.loads(v)
        except json.JSONDecodeError:
            params[k] = v
    cal = _load_cal(a.calibration, dev) if a.calibration else None
    rec = simulate(dev, a.motion, effects=effects, seed=a.seed, calibration=cal, **params)
    write_recording(a.output, rec)
    return 0


def _jig_accuracy(text) -> float:
    """--jig-accuracy DEG: a finite angle >= 0 (one-line error naming the option otherwise)."""
    try:
        v = float(text)
    except ValueError:
        v = float("nan")
    if not (np.isfinite(v) and v >= 0):
        raise AccelcalError(f"--jig-accuracy {text!r}: expected a finite angle in degrees >= 0 (the rms "
                            "rotation angle of the jig's pose errors; 0 = exact references)")
    return v


def cmd_calibrate(a):
    from .calibrate import calibrate_recordings
    from .calibration import save_calibration
    from .recording import read_recording
    jig = _jig_accuracy(a.jig_accuracy)
    dev = _load_device(a.device)
    recs = [read_recording(p, dev.n_channels) for p in a.recordings]
    cal = calibrate_recordings(dev, recs, method=a.method, jig_accuracy_deg=jig)
    fit = cal.extra.get("fit", {}) if isinstance(cal.extra, dict) else {}
    hint = fit.get("jig_accuracy_consistent_with_scatter_deg")
    if hint is not None:
        print(f"accelcal calibrate: warning: the poses scatter about the fit far beyond their noise (chi2/dof "
              f"{fit['chi2'] / fit['dof']:.3g}), as a jig error of about {hint:.2g} deg would; if the jig is that "
              f"inaccurate, state it with --jig-accuracy (else the offsets absorb it)", file=sys.stderr)
    save_calibration(cal, a.output)
    return 0


ESTIMATORS = {"attitude": attitude_from_recording, "displacement": displacement_from_recording,
              "rate": rate_from_recording}


def run_estimator(kind: str, device_path, calibration_path, recording_path, output, *, engine: str = "float",
                  report=None, **options) -> list[str]:
    """`accelcal attitude|displacement|rate --device D --calibration C REC -o OUT [--engine] [--report DIR]`.

    Load, estimate, write the CSV (atomically) and, with ``report``, the plots.

    Parameters
    ----------
    kind : {"attitude", "displacement", "rate"}
    device_path, calibration_path, recording_path : path
        Inputs (device "default" or None: the seed prototype).
    output : path
        The result CSV.
    engine : {"float", "fixed"}
    report : path, optional
        Directory for the plots.
    **options
        To the estimator (attitude: gain, w2_gate, leak_tau_s; displacement: form, axis;
        rate: leak_tau_s).

    Returns
    -------
    list of str
        The warnings, one line each, for the caller to print to stderr.

    Raises
    ------
    AccelcalError
        Bad input (one line), before anything is written.
    """
    fn = ESTIMATORS.get(kind)
    if fn is None:
        raise ValueError(f"unknown estimator {kind!r}")
    dev = _load_device(device_path)
    cal = _load_cal(calibration_path, dev)
    rec = read_recording(recording_path, dev.n_channels)
    cols = fn(dev, cal, rec, engine, **options)
    write_columns_csv(output, cols, cols.meta)
    if report is not None:
        report_plots(report, cols, rec, kind)
    return [f"accelcal {kind}: warning: {w}" for w in cols.warnings]


def _estimator(a, kind):
    options = {k: v for k, v in (("axis", getattr(a, "axis", None)), ("form", getattr(a, "form", None)))
               if v is not None}
    for w in run_estimator(kind, a.device, a.calibration, a.recording, a.output, engine=a.engine,
                           report=a.report, **options):
        print(w, file=sys.stderr)
    return 0


def cmd_attitude(a):
    return _estimator(a, "attitude")


def cmd_displacement(a):
    return _estimator(a, "displacement")


def cmd_rate(a):
    return _estimator(a, "rate")


def cmd_diagnose(a):
    from .diagnose import diagnose, write_report
    from .recording import read_recording
    dev = _load_device(a.device)
    cal = _load_cal(a.calibration, dev)
    recs = [read_recording(p, dev.n_channels) for p in a.recordings]
    with _progress("diagnose: scoring candidates", unit=" fits") as bar:
        def scored(name):
            bar.set_postfix_str(name, refresh=False)
            bar.update()
        result = diagnose(dev, cal, recs, folds=a.folds, seed=a.seed, progress=scored)
    # the result is the contract's JSON object; it also carries the per-sample
    # series the report plots, so it goes to write_report as it is
    atomic_write(a.json, lambda f: json.dump(result, f, indent=2, default=_json_default))
    if a.report:
        from .report import REPORT_FILES
        with _progress("diagnose: writing the report", total=REPORT_FILES, unit=" files") as bar:
            write_report(result, a.report, progress=lambda path: bar.update())
    print(f"verdict: {result.get('verdict')}")
    return 0


def _json_default(o):
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def cmd_demo(a):
    from .demo import run_demo
    return run_demo(out_dir=Path(a.out), seed=a.seed)


def _simulate_epilog() -> str:
    from .effects import describe_effects
    from .motions import describe_motions
    return "motions:\n" + describe_motions() + "\n\neffects:\n" + describe_effects()


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="accelcal", description=__doc__.splitlines()[0])
    from . import __version__
    p.add_argument("--version", action="version", version=f"accelcal {__version__}")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")

    s = sub.add_parser("demo", help="simulate, calibrate, emit the header, resolve with the C core, "
                       "diagnose, on the seed's 6-channel r = 60 mm prototype")
    s.add_argument("--out", default="accelcal-demo", help="directory for the demo's files")
    s.add_argument("--seed", type=int, default=1)
    s.set_defaults(func=cmd_demo)

    s = sub.add_parser("simulate", help="simulate a recording", epilog=_simulate_epilog(),
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    s.add_argument("--device", required=True, help="device JSON ('default' = the seed prototype)")
    s.add_argument("--motion", required=True, help="motion profile name")
    s.add_argument("--effect", action="append", default=[], metavar="NAME[:k=v,...]",
                   help="unmodelled effect to put in the data (repeatable)")
    s.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="motion parameter (repeatable; JSON values)")
    s.add_argument("--calibration", help="true channel parameters (default: the device's nominal)")
    s.add_argument("--seed", type=int, default=0)
    s.add_argument("-o", "--output", required=True)
    s.set_defaults(func=cmd_simulate)

    s = sub.add_parser("calibrate", help="estimate a calibration")
    s.add_argument("--device", required=True)
    s.add_argument("recordings", nargs="+", metavar="REC.csv")
    s.add_argument("--method", choices=["full", "gain", "offset", "jigfree"], default=None)
    from .calibrate import JIG_ACCURACY_DEG
    s.add_argument("--jig-accuracy", metavar="DEG", default=f"{JIG_ACCURACY_DEG:g}",
                   help="known poses: the jig's accuracy, as the rms angle (deg) by which a pose may be rotated "
                   "from its reference f.  The pose directions are then estimated jointly with the channel "
                   "parameters, each reference a prior of that accuracy (one pose error moves all of a pose's "
                   "channels together), and the uncertainties and chi2 include the priors; the result stays in "
                   "the jig's frame.  Default %(default)s: the references are exact (ordinary least squares, at "
                   "the Cramer-Rao bound with honest uncertainties for a perfect jig; stating 0.5 deg there costs "
                   "1.4x the bound in offset error).  On a jig that is really off by 0.5-2 deg, 0 gives 18-30x "
                   "larger offset errors on +-x,+-y,+-z than stating it, and 16-61x the bound on 24 general "
                   "poses (a warning names the accuracy the residuals imply): state your jig's accuracy.  "
                   "Ignored by jigfree")
    s.add_argument("-o", "--output", required=True)
    s.set_defaults(func=cmd_calibrate)

    s = sub.add_parser("header", help="emit the C header for firmware")
    s.add_argument("--device", required=True)
    s.add_argument("--calibration", required=True)
    s.add_argument("--prefix", default="AC_CAL", help="C identifier prefix (default AC_CAL)")
    s.add_argument("-o", "--output", required=True)
    s.set_defaults(func=cmd_header)

    s = sub.add_parser("resolve", help="per-sample f and alpha")
    s.add_argument("--device", required=True)
    s.add_argument("--calibration", required=True)
    s.add_argument("recording", metavar="REC.csv")
    s.add_argument("--engine", choices=["float", "fixed"], default="float")
    s.add_argument("--omega", choices=["auto", "reference", "none"], default="auto",
                   help="omega for the centripetal correction (auto: the w_* columns when complete)")
    s.add_argument("-o", "--output", required=True)
    s.set_defaults(func=cmd_resolve)

    for name, func, what in (("attitude", cmd_attitude, "pendulum attitude from two triads: t, theta_rad, w_y, dw_y"),
                             ("displacement", cmd_displacement, "stop-to-stop displacement: t, v_*, p_*"),
                             ("rate", cmd_rate, "angular rate from alpha, leaky integration reset on rest")):
        s = sub.add_parser(name, help=what)
        s.add_argument("--device", required=True)
        s.add_argument("--calibration", required=True)
        s.add_argument("recording", metavar="REC.csv")
        s.add_argument("--engine", choices=["float", "fixed"], default="float")
        s.add_argument("--report", metavar="DIR", help="write plots into DIR")
        s.add_argument("-o", "--output", required=True)
        if name == "displacement":
            s.add_argument("--axis", choices=["x", "y", "z"],
                           help="1-D along this body axis (the seed's actuator; nothing removed)")
            s.add_argument("--form", choices=["offline", "stream"],
                           help="float engine: offline (default) or the firmware's streaming form")
        s.set_defaults(func=func)

    s = sub.add_parser("diagnose", help="sim-to-real diagnosis: where the gap lies, which effect, how far "
                       "it shrinks")
    s.add_argument("--device", required=True)
    s.add_argument("--calibration", required=True)
    s.add_argument("recordings", nargs="+", metavar="REC.csv")
    s.add_argument("--json", required=True, metavar="OUT.json")
    s.add_argument("--report", metavar="DIR", help="plots and a written summary")
    s.add_argument("--folds", type=int, default=5, help="blocked cross-validation folds")
    s.add_argument("--seed", type=int, default=0)
    s.set_defaults(func=cmd_diagnose)
    return p


def main(argv=None) -> int:
    parser = build_parser()
    a = parser.parse_args(argv)
    try:
        return int(a.func(a) or 0)
    except AccelcalError as e:
        print(f"accelcal {a.command}: error: {e}", file=sys.stderr)
        return EXIT_INPUT
    except np.linalg.LinAlgError as e:
        # a degenerate calibration or geometry that no loader check could see
        print(f"accelcal {a.command}: error: the inputs are numerically degenerate ({e})", file=sys.stderr)
        return EXIT_INPUT
    except KeyboardInterrupt:
        print(f"accelcal {a.command}: interrupted", file=sys.stderr)
        return 130
    except Exception as e:  # noqa: BLE001 - one line, never a traceback
        print(f"accelcal {a.command}: internal error: {type(e).__name__}: {e}", file=sys.stderr)
        return EXIT_INTERNAL


if __name__ == "__main__":
    sys.exit(main())
