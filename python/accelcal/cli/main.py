"""The ``accelcal`` command (forms fixed by the data contract, docs/data-contract.md).

Every subcommand exits 0 on success; on bad input it prints one line to stderr (no traceback) and
exits 2, leaving no partial output file (all outputs are written through errors.atomic_write).
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
from tqdm import tqdm

from .. import __version__
from ..calibrate import JIG_ACCURACY_AUTO, JIGFREE_MODELS, calibrate_recordings
from ..io.calibration import load_calibration, save_calibration
from .calibrate_command import calibration_summary, jig_accuracy_arg, min_static_arg, record_warnings, reduced_recordings
from .paths import check_not_an_input, check_output, check_output_dir
from .convert_command import add_convert_parser
from .capture_command import add_capture_parser
from .refine_command import add_refine_parser
from .demo import run_demo
from ..io.device import default_device, load_device
from ..diagnose import diagnose
from ..effects import describe_effects, params_to_json, parse_effect_spec
from ..errors import AccelcalError, atomic_write
from ..estimators import OMEGA_SOURCES, choose_omega_engine, omega_columns
from ..firmware.header import calibration_header
from ..motions import describe_motions
from ..io.recording import read_recording, write_columns_csv, write_recording
from ..io.thinned import MAX_SAMPLES, check_max_samples, read_all_thinned
from ..report import REPORT_FILES, write_report
from ..resolve import clipped_samples, resolve_recording
from ..resolve_stream import resolve_warnings, result_names
from .resolve_command import add_estimator_options, stream_resolve
from .estimator_command import estimator_command, reader_notes, run_estimator, time_note  # noqa: F401
from ..simulate import run_simulation
from ..readings.static import MIN_POSE_S
from ..io.units_cli import add_units_options, scale_from_args

EXIT_INPUT = 2
EXIT_INTERNAL = 3


def _load_device(path):
    return default_device() if path in (None, "default") else load_device(path)


def _read(paths, device, command: str, a=None, max_samples: int | None = None) -> list:
    """Read recordings (in the units --units/--lsb/--full-scale state, with the file's
    comments: units_cli, units.file_scale); mention once, on stderr, the columns that are
    ignored.  ``max_samples``: a longer recording is read as evenly spaced windows of about
    that many samples (io.thinned; 0: every sample)."""
    scale = None if a is None else scale_from_args(a, device, reader=True)
    seen: dict[Path, str] = {}
    for p in paths:
        key = Path(p).resolve()
        if key in seen:
            raise AccelcalError(f"{p}: the same recording as {seen[key]} (given twice, its poses would count twice)")
        seen[key] = str(p)
    if max_samples is None:
        recs = [read_recording(p, device.n_channels, scale=scale) for p in paths]
    else:
        recs = read_all_thinned(list(paths), device, max_samples, scale)
    for r in recs:
        for line in reader_notes(r, command):
            print(line, file=sys.stderr)
        time_note(r, device, command)
    ignored = sorted({k for r in recs for k in r.extra})
    if ignored:
        print(f"accelcal {command}: note: ignored column{'s' if len(ignored) > 1 else ''} "
              f"{', '.join(ignored)} (not part of the accelerometer model)", file=sys.stderr)
    return recs


def _write_csv(path, header: list[str], columns: list[np.ndarray], comments: dict):
    write_columns_csv(path, dict(zip(header, columns)), comments)


def _progress(desc: str, total: int | None = None, unit: str = " steps", quiet: bool = False):
    """A progress bar on stderr for work that takes seconds on long recordings.  Off when
    stderr is not a terminal (tqdm's disable=None): pipes, logs and scripts see only the
    one-line messages."""
    return tqdm(desc=desc, total=total, unit=unit, file=sys.stderr, disable=True if quiet else None, leave=False,
                dynamic_ncols=True)


# ---- subcommands -------------------------------------------------------------

def cmd_resolve(a):
    check_output(a.output)
    dev = _load_device(a.device)
    cal = load_calibration(a.calibration, dev)
    if not a.whole_file and stream_resolve(a, dev, cal):
        return 0
    rec, = _read([a.recording], dev, "resolve", a)
    est = choose_omega_engine(dev, cal, rec, a.omega, a.engine)
    f, al, flags = resolve_recording(dev, cal, rec, a.engine, a.omega, None if est is None else est.for_resolver())
    comments = {"engine": a.engine, "device": dev.name, **({"omega": "array"} if est is not None else {})}
    clipped, clip_warnings = clipped_samples(rec, dev)
    for w in resolve_warnings(0 if flags is None else int(np.count_nonzero(flags)), clip_warnings):
        print(w, file=sys.stderr)
    cols = [rec.t, f[:, 0], f[:, 1], f[:, 2], al[:, 0], al[:, 1], al[:, 2]]
    names = result_names(flags is not None, bool(clip_warnings))
    if est is not None:
        names[7:7] = list(omega_columns(est))
        cols += list(omega_columns(est).values())
    if flags is not None:
        cols.append(flags.astype(float))
    if clip_warnings:
        cols.append(clipped.astype(float))
    _write_csv(a.output, names, cols, comments)
    return 0


def cmd_header(a):
    check_output(a.output)
    dev = _load_device(a.device)
    cal = load_calibration(a.calibration, dev)
    text = calibration_header(dev, cal, prefix=a.prefix)
    atomic_write(a.output, lambda f: f.write(text))
    return 0


def cmd_simulate(a):
    check_output(a.output)
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
    cal = load_calibration(a.calibration, dev) if a.calibration else None
    sim = run_simulation(dev, a.motion, effects=effects, seed=a.seed, calibration=cal, **params)
    write_recording(a.output, sim.recording)
    for name in sim.unchanged:
        print(f"accelcal simulate: note: effect {name} changed no reading ({params_to_json(sim.effects[name])}): "
              "the motion never reaches it; see 'accelcal simulate --help' for its parameters", file=sys.stderr)
    return 0


def cmd_calibrate(a):
    check_output(a.output)
    jig = jig_accuracy_arg(a.jig_accuracy)
    min_static = min_static_arg(a.min_static)
    dev = _load_device(a.device)
    recs = reduced_recordings(a.recordings, dev, a) or _read(a.recordings, dev, "calibrate", a)
    cal = calibrate_recordings(dev, recs, method=a.method, jig_accuracy_deg=jig, jigfree_model=a.jigfree_model,
                               drop_outliers=a.drop_outliers, min_static_s=min_static)
    warnings = record_warnings(dev, cal)
    save_calibration(cal, a.output)
    for n in cal.extra.get("notes", []) if isinstance(cal.extra, dict) else []:
        print(f"accelcal calibrate: note: {n}", file=sys.stderr)
    for w in warnings:
        print(f"accelcal calibrate: warning: {w}", file=sys.stderr)
    print(calibration_summary(cal, len(recs), a.output))
    return 0


def cmd_attitude(a):
    return estimator_command(a, "attitude")


def cmd_displacement(a):
    return estimator_command(a, "displacement")


def cmd_rate(a):
    return estimator_command(a, "rate")


def cmd_diagnose(a):
    check_output(a.json, "--json")
    if a.report:
        check_output_dir(a.report, "--report")
    dev = _load_device(a.device)
    cal = load_calibration(a.calibration, dev)
    if isinstance(cal.extra, dict):
        cal.extra["source"] = str(a.calibration)          # named so in the JSON's calibration.source
    recs = _read(a.recordings, dev, "diagnose", a, max_samples=a.max_samples)
    with _progress("diagnose: scoring candidates", unit=" fits", quiet=a.quiet) as bar:
        def scored(name):
            bar.set_postfix_str(name, refresh=False)
            bar.update()
        result = diagnose(dev, cal, recs, folds=a.folds, seed=a.seed, progress=scored,
                          outliers="drop" if a.drop_outliers else "name", max_samples=a.max_samples)
    # the result is the contract's JSON object; it also carries the per-sample
    # series the report plots, so it goes to write_report as it is
    atomic_write(a.json, lambda f: json.dump(result, f, indent=2, default=_json_default))
    if a.report:
        with _progress("diagnose: writing the report", total=REPORT_FILES, unit=" files", quiet=a.quiet) as bar:
            write_report(result, a.report, progress=lambda path: bar.update())
    print(f"verdict: {result.get('verdict')}")
    return 0


def _max_samples(text: str) -> int:
    try:
        return check_max_samples(int(text))
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e) if "max_samples" in str(e) else f"expected an integer, got {text!r}") from None


def _json_default(o):
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def cmd_demo(a):
    return run_demo(out_dir=Path(a.out), seed=a.seed)


def _simulate_epilog() -> str:
    return "motions:\n" + describe_motions() + "\n\neffects:\n" + describe_effects()


_DEVICE = "device description JSON (docs/data-contract.md), or 'default' for the seed's 6-channel prototype"
_CAL = ("calibration JSON, as written by accelcal calibrate, or 'nominal': the device file's datasheet values "
        "(zero_counts, counts_per_mps2 along each axis)")
_REC = "recording CSV (docs/data-contract.md)"
_DESCRIPTION = ("calibration, 6-DOF resolution and sim-to-real diagnosis for accelerometer-only\n"
                "motion sensors, with an integer-only C core for MCU firmware")
_DOCS = """documentation, in the repository:
  docs/getting-started.md  the commands and the Python API
  docs/data-contract.md    device, calibration and recording files, command forms
  docs/diagnosis-json.md   the diagnosis's JSON
the site (bash tools/build_docs.sh): build/docs/html/index.html, the same pages with
worked examples and the API reference; data-contract.html is the data contract."""
_RECS = "one or more recording CSVs of the same device"
_ENGINE = "float: the float64 reference; fixed: the C core with exactly the header's constants"
_OUT_CSV = "the CSV to write (written atomically: no partial file on error)"


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="accelcal", description=_DESCRIPTION, epilog=_DOCS,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--version", action="version", version=f"accelcal {__version__}")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")

    s = sub.add_parser("demo", help="simulate, calibrate, emit the header, resolve with the C core, "
                       "diagnose, on the seed's 6-channel r = 60 mm prototype")
    s.add_argument("--out", default="accelcal-demo", help="directory for the demo's files")
    s.add_argument("--seed", type=int, default=1, help="random seed of the simulated data (default %(default)s)")
    s.set_defaults(func=cmd_demo)

    s = sub.add_parser("simulate", help="simulate a recording", epilog=_simulate_epilog(),
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    s.add_argument("--device", required=True, metavar="D.json", help=_DEVICE)
    s.add_argument("--motion", required=True, help="motion profile name")
    s.add_argument("--effect", action="append", default=[], metavar="NAME[:k=v,...]",
                   help="unmodelled effect to put in the data (repeatable)")
    s.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="motion parameter (repeatable; JSON values)")
    s.add_argument("--calibration", help="true channel parameters (default: the device's nominal)")
    s.add_argument("--seed", type=int, default=0, help="random seed (noise, random effect values; default %(default)s)")
    s.add_argument("-o", "--output", required=True, metavar="REC.csv", help=_OUT_CSV)
    s.set_defaults(func=cmd_simulate)

    s = sub.add_parser("calibrate", help="estimate a calibration")
    s.add_argument("--device", required=True, metavar="D.json", help=_DEVICE)
    s.add_argument("recordings", nargs="+", metavar="REC.csv", help=_RECS)
    s.add_argument("--method", choices=["full", "gain", "offset", "jigfree"], default=None,
                   help="full: offset + sensitivity vector per channel from known poses (the default when the "
                   "recordings give reference f); gain: offset + gain along the nominal axis; offset: offset "
                   "only; jigfree: no reference needed, static intervals found and |f| = g (the default when "
                   "the recordings have no reference)")
    s.add_argument("--jig-accuracy", metavar="DEG", default=JIG_ACCURACY_AUTO,
                   help="known poses: the jig's accuracy, as the rms angle (deg) by which a pose may be rotated "
                   "from its reference f.  The pose directions are then estimated jointly with the channel "
                   "parameters, each reference a prior of that accuracy (one pose error moves all of a pose's "
                   "channels together), and the uncertainties and chi2 include the priors; the result stays in "
                   "the jig's frame.  0: the references are exact (ordinary least squares, at the Cramer-Rao "
                   "bound for a perfect jig).  Default %(default)s: estimated from the poses' scatter about the "
                   "fit (empirical Bayes: the marginal likelihood of the pose means over the jig accuracy) and "
                   "used where the likelihood-ratio test rejects a perfect jig at 5 %%, else 0; the summary "
                   "says which, with the value and its 95 %% interval (docs/calibration-jig.md).  Ignored by "
                   "jigfree")
    s.add_argument("--jigfree-model", choices=JIGFREE_MODELS, default="auto",
                   help="jigfree: the channel model.  full: offset + sensitivity vector per channel (needs 9 pose "
                   "orientations for a triad); gain: offset + gain along the nominal axis (6); offset: offset only "
                   "(3).  auto (the default): full, or where the poses do not determine it (too few "
                   "orientations, a degenerate spread, no convergence) the first of gain and offset they do, "
                   "with a warning that says why")
    s.add_argument("--drop-outliers", action="store_true",
                   help="leave out the poses far off the fit (residual over the noise beyond the poses' median + 8 "
                   "robust sd: a knock, a pose not held, a wrong row), which are otherwise kept and named in a "
                   "warning with how much the fit changes without them")
    s.add_argument("--min-static", metavar="SECONDS", default=f"{MIN_POSE_S:g}",
                   help="recordings without 'pose' labels: the shortest still stretch the static detector takes "
                   "for a pose where a motion touches it (default %(default)s s: a pause in a hand's movement is "
                   "none).  A robot arm that stops 0.75 s at each pose: --min-static 0.7 (the errors and warnings "
                   "count the stretches left out as shorter).  Below the detector's 0.5 s window it acts as the "
                   "window; a stretch joined to its neighbours by instant steps (a logger of static blocks) needs "
                   "one window whatever it says")
    s.add_argument("-o", "--output", required=True, metavar="CAL.json", help="the calibration JSON to write")
    add_units_options(s)
    s.set_defaults(func=cmd_calibrate)

    s = sub.add_parser("header", help="emit the C header for firmware")
    s.add_argument("--device", required=True, metavar="D.json", help=_DEVICE)
    s.add_argument("--calibration", required=True, metavar="CAL.json", help=_CAL)
    s.add_argument("--prefix", default="AC_CAL", help="C identifier prefix (default AC_CAL)")
    s.add_argument("-o", "--output", required=True, metavar="NAME.h", help="the C header to write")
    s.set_defaults(func=cmd_header)

    s = sub.add_parser("resolve", help="per-sample f and alpha")
    s.add_argument("--device", required=True, metavar="D.json", help=_DEVICE)
    s.add_argument("--calibration", required=True, metavar="CAL.json", help=_CAL)
    s.add_argument("recording", metavar="REC.csv", help=_REC)
    s.add_argument("--engine", choices=["float", "fixed"], default="float", help=_ENGINE)
    s.add_argument("--omega", choices=OMEGA_SOURCES, default="auto",
                   help="omega for the centripetal correction: reference (the w_* columns), none, array (the "
                   "accelerometers' own, docs/angular-rate.md: adds w_x, w_y, w_z and their 1-sigma w_*_sigma); "
                   "auto: the w_* columns when complete, else array where the layout observes omega")
    s.add_argument("-o", "--output", required=True, metavar="OUT.csv", help="t, f_*, dw_* (.parquet: Parquet)")
    s.add_argument("--whole-file", action="store_true", help="read the whole recording first (docs/streaming.md)")
    s.add_argument("--quiet", action="store_true", help="no progress bar on stderr")
    add_units_options(s)
    s.set_defaults(func=cmd_resolve)

    for name, func, what in (("attitude", cmd_attitude, "pendulum attitude from two triads: t, theta_rad, w_y, dw_y"),
                             ("displacement", cmd_displacement, "stop-to-stop displacement: t, v_*, p_*"),
                             ("rate", cmd_rate, "angular rate from alpha, leaky integration reset on rest")):
        s = sub.add_parser(name, help=what)
        s.add_argument("--device", required=True, metavar="D.json", help=_DEVICE)
        s.add_argument("--calibration", required=True, metavar="CAL.json", help=_CAL)
        s.add_argument("recording", metavar="REC.csv", help=_REC)
        s.add_argument("--engine", choices=["float", "fixed"], default="float", help=_ENGINE)
        s.add_argument("--report", metavar="DIR", help="write plots into DIR")
        s.add_argument("-o", "--output", required=True, metavar="OUT.csv", help=_OUT_CSV)
        if name in ("rate", "attitude", "displacement"):
            s.add_argument("--whole-file", action="store_true", help="read the whole recording first (docs/streaming.md)")
            s.add_argument("--quiet", action="store_true", help="no progress bar on stderr")
        if name == "rate":
            s.add_argument("--omega", choices=["alpha", "array"], default="alpha",
                           help="alpha: leaky integration of alpha, reset on rest; array: the accelerometers' own "
                           "omega fused with the integrated alpha, with w_*_sigma (docs/angular-rate.md)")
        if name == "displacement":
            s.add_argument("--axis", choices=["x", "y", "z"],
                           help="1-D along this body axis (the seed's actuator; nothing removed)")
            s.add_argument("--form", choices=["offline", "stream"],
                           help="float engine: offline (default) or the firmware's streaming form")
            s.add_argument("--keep-turned", action="store_true",
                           help="write a motion during which the body turned (its zero point beyond what a "
                           "calibration or tilt error gives), with a warning; by default it is left out, and the "
                           "output ends at the rest before it")
            s.add_argument("--resample", action="store_true",
                           help="interpolate the samples from their time stamps onto a uniform grid first (stamps "
                           "that keep no uniform grid: a sensor read on a loop whose period varies, a driver that "
                           "stamps each sample as it reads it); a gap of one lost sample (a step beyond 1.8 x "
                           "the median, up to 2.5 regular steps) is bridged with a note, a longer one refused")
        add_estimator_options(s, name)
        s.set_defaults(func=func)

    s = sub.add_parser("diagnose", help="sim-to-real diagnosis: where the gap lies, which effect, how far "
                       "it shrinks")
    s.add_argument("--device", required=True, metavar="D.json", help=_DEVICE)
    s.add_argument("--calibration", required=True, metavar="CAL.json", help=_CAL)
    s.add_argument("recordings", nargs="+", metavar="REC.csv", help=_RECS)
    s.add_argument("--json", required=True, metavar="OUT.json", help="the diagnosis (format: docs/diagnosis-json.md)")
    s.add_argument("--report", metavar="DIR", help="plots and a written summary")
    s.add_argument("--folds", type=int, default=5, help="blocked cross-validation folds")
    s.add_argument("--seed", type=int, default=0, help="seed of the cross-validation folds (default %(default)s)")
    s.add_argument("--drop-outliers", action="store_true",
                   help="set aside the static poses far off the calibration's terms fitted to the poses (calibrate's "
                   "rule: a knocked or mislabelled pose), which are otherwise kept, named in the JSON's 'outliers' "
                   "with the diagnosis of the other poses, and in a note")
    s.add_argument("--max-samples", type=_max_samples, default=MAX_SAMPLES, metavar="N",
                   help="a recording of more samples is diagnosed on evenly spaced windows of about N of them, "
                   "read in bounded memory (JSON: recordings[].thinned); 0: every sample (default %(default)s)")
    s.add_argument("--quiet", action="store_true", help="no progress bars on stderr")
    add_units_options(s)
    s.set_defaults(func=cmd_diagnose)
    add_convert_parser(sub, check_output)
    add_capture_parser(sub, check_output)
    add_refine_parser(sub)
    return p


def main(argv=None) -> int:
    parser = build_parser()
    a = parser.parse_args(argv)
    try:
        check_not_an_input(a)
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
