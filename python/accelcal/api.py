"""The Python API: ``import accelcal as ac``.

Each function takes the package's objects (:class:`~accelcal.io.device.Device`,
:class:`~accelcal.io.recording.Recording`, :class:`~accelcal.io.calibration.Calibration`),
file paths, or numpy arrays, and does what the command of the same name does,
without writing files unless asked::

    import accelcal as ac
    dev = ac.load_device("mpu6050.json")
    rec = ac.read_recording("poses.csv", dev)
    cal = ac.calibrate(dev, rec)                 # known poses or jig-free, as the data allow
    ac.save_calibration(cal, "cal.json")
    text = ac.header(dev, cal)                   # the firmware header, as a string
    out = ac.resolve(dev, cal, rec, engine="fixed")
    out.f[:3]                                    # m/s^2, from the C core

Errors in the inputs raise :class:`~accelcal.errors.AccelcalError` (its subclass
:class:`~accelcal.errors.InputError` names file, row or field) with one line of text.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Iterable

import numpy as np

from .calibrate import calibrate_recordings
from .calibrate.refine import RefineResult, refine
from .io.calibration import Calibration, load_calibration, save_calibration
from .cli.calibrate_command import record_warnings
from .io.device import Device, default_device, load_device, save_device
from .diagnose import diagnose as _diagnose_impl
from .errors import AccelcalError, atomic_write, options_checked
from .estimators import Columns, attitude_from_recording, choose_omega_engine, displacement_from_recording, rate_from_recording
from .firmware.header import calibration_header
from .motions import MOTIONS, Motion
from .io.recording import Recording, read_recording as _read_recording_file, write_recording
from .convert.formats import Converted, convert_file
from .resolve import ResolveResult, clipped_samples, resolve_recording
from .io.units import stated_scale
from .simulate import simulate as _simulate_impl
from .readings.static import MIN_POSE_S

__all__ = ["Device", "Recording", "Calibration", "Columns", "ResolveResult", "AccelcalError",
           "default_device", "load_device", "save_device", "read_recording", "write_recording",
           "load_calibration", "save_calibration", "as_recording", "calibrate", "refine", "RefineResult", "resolve",
           "diagnose",
           "header", "simulate", "attitude", "displacement", "rate", "convert", "Converted"]


def motion_params(device: Any = None, motion: Any = None, *args: Any, **kwargs: Any) -> list[str] | None:
    """The parameters :func:`simulate`'s ``motion`` takes (a registered name, a spec string
    ``"name:k=v"`` or a Motion; none for a ready trajectory), or None where the name is not a
    motion's (simulate's refusal names the motions)."""
    if isinstance(motion, Motion):
        return [p.name for p in motion.all_params]
    if isinstance(motion, str):
        m = MOTIONS.get(motion.split(":")[0].strip())
        return None if m is None else [p.name for p in m.all_params]
    return []


def as_device(device: Any) -> Device:
    """A Device from a Device, a JSON path, or ``"default"`` / None (the seed prototype)."""
    if isinstance(device, Device):
        return device
    if device is None or (isinstance(device, str) and device == "default"):
        return default_device()
    if isinstance(device, (str, Path)):
        return load_device(device)
    raise TypeError(f"device: expected a Device, a JSON path or 'default', not {type(device).__name__}")


def as_calibration(calibration: Any, device: Device) -> Calibration:
    """A Calibration from a Calibration or a JSON path (checked against ``device``)."""
    if isinstance(calibration, Calibration):
        return calibration
    if isinstance(calibration, (str, Path)):
        return load_calibration(calibration, device)
    raise TypeError(f"calibration: expected a Calibration or a JSON path, not {type(calibration).__name__}")


@options_checked()
def read_recording(path: Any, device: Any = None, *, units: str | None = None, lsb: float | None = None,
                   full_scale_g: float | None = None, bits: int = 16,
                   gravity_mps2: float | None = None) -> Recording:
    """Read a recording CSV (the data contract's format).

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file (compressed -- gzip, bzip2, xz, zstd, a zip of one file -- or
        whitespace-separated text too).
    device : Device, path or int, optional
        When given, the file must have that device's ``raw_0 .. raw_{N-1}`` (an int is N).
    units : {"counts", "mps2", "mmps2", "g", "mg"}, optional
        The unit of the file's raw readings (as ``--units``); m/s^2 or g with ``lsb`` (one
        count in that unit) or ``full_scale_g`` (+-range in g at ``bits`` bits; m/s^2 with
        ``gravity_mps2``, default 9.80665).  The readings become counts exactly (a value
        printed with few digits, as '%g' does, is the count it rounds to where its last
        digit's half unit is at most a quarter of a count), or the first that is not a whole
        number of LSBs is refused with its row.  Default: the
        file's ``# units:`` / ``# lsb:`` comments, else counts; stated by both, they must
        agree.
    lsb, full_scale_g, bits, gravity_mps2
        One count in ``units`` (float, or str with a unit: "1mg"), or the +-range in g at
        ``bits`` bits (default 16; g in m/s^2 for m/s^2 readings, default 9.80665).

    Returns
    -------
    Recording
        Raw readings in counts.

    Raises
    ------
    AccelcalError
        Bad input (one line naming the file, row and column); a comment that
        contradicts ``units``/``lsb``/``full_scale_g`` (naming the comment's line).

    Examples
    --------
    >>> rec = ac.read_recording("phone.csv", dev, units="mps2", lsb=9.81 / 2048)   # doctest: +SKIP
    """
    n = device if isinstance(device, int) else (None if device is None else as_device(device).n_channels)
    return _read_recording_file(path, n, scale=stated_scale(units, lsb, full_scale_g, bits, gravity_mps2))


@options_checked()
def as_recording(recording: Any, device: Device) -> Recording:
    """A Recording from a Recording, a CSV path, or an (n, N) array of raw counts.

    Parameters
    ----------
    recording : Recording, path or array_like
        An array is taken as integer raw counts, one row per sample, sampled at the
        device's ``sample_rate_hz`` from t = 0, with no reference columns; a 1-D array of
        one count per channel is one sample.
    device : Device

    Returns
    -------
    Recording

    Raises
    ------
    AccelcalError
        An array of the wrong shape, or with values that are not integers.
    """
    if isinstance(recording, Recording):
        return recording
    if isinstance(recording, (str, Path)):
        return _read_recording_file(recording, device.n_channels)
    raw = np.asarray(recording)
    if raw.ndim == 1 and raw.shape[0] == device.n_channels:     # one reading: one sample
        raw = raw[None, :]
    if raw.ndim != 2 or raw.shape[1] != device.n_channels:
        raise AccelcalError(f"raw counts: expected an (n, {device.n_channels}) array for device "
                            f"{device.name!r}, got shape {raw.shape}")
    if raw.dtype.kind == "f":
        if not np.all(np.isfinite(raw)) or np.any(raw != np.round(raw)):
            bad = int(np.argmax(~np.isfinite(raw).all(axis=1) | (raw != np.round(raw)).any(axis=1)))
            raise AccelcalError(f"<array>: row {bad + 1}: not integer counts ({raw[bad].tolist()}; rows counted "
                                "from 1, as in every message)")
    elif raw.dtype.kind not in "iu":
        raise AccelcalError(f"raw counts: expected integers, got dtype {raw.dtype}")
    t = np.arange(raw.shape[0]) / float(device.sample_rate_hz)
    return Recording(t=t, raw=raw.astype(np.int64), source="<array>")


def _as_recordings(recordings: Any, device: Device) -> list[Recording]:
    """Recordings from one (a Recording, a path, an array) or a sequence of them; a sequence
    of rows of numbers (``raw.tolist()``: every item a 1-D list, tuple or array of numbers, as
    long as each other) is one (n, N) array, as :func:`as_recording` reads it, not n
    recordings of one sample each."""
    if isinstance(recordings, (Recording, str, Path, np.ndarray)):
        return [as_recording(recordings, device)]
    items = list(recordings)
    if items and all(isinstance(r, (list, tuple, np.ndarray)) and np.ndim(r) == 1 and len(r) == len(items[0]) and
                     all(isinstance(v, (int, float, np.number)) and not isinstance(v, bool) for v in r)
                     for r in items):
        return [as_recording(np.asarray(items), device)]
    return [as_recording(r, device) for r in items]


@options_checked()
def calibrate(device: Any, recordings: Any, method: str | None = None, *,
              jig_accuracy_deg: float | str = "auto", jigfree_model: str = "auto", drop_outliers: bool = False,
              min_static_s: float = MIN_POSE_S) -> Calibration:
    """Estimate a calibration from static poses (as ``accelcal calibrate``).

    Parameters
    ----------
    device : Device, path or "default"
    recordings : Recording, path, array or a sequence of them
        Poses come from the ``pose`` labels when present, else from static detection.  A
        list of rows of numbers (``raw.tolist()``) is one array, not a recording a row.
    method : {"full", "gain", "offset", "jigfree"}, optional
        Default: ``full`` when every pose has a reference f, ``jigfree`` when none has.
    jig_accuracy_deg : float or "auto"
        Known poses: the rms angle (deg) the jig's poses may be off; "auto": estimated (docs/calibration-jig.md).
    jigfree_model : {"auto", "full", "gain", "offset"}
        Jig-free: the channel model; ``auto`` is ``full``, or, where the poses do not
        determine it, the first of ``gain`` and ``offset`` they do (the reason in
        ``extra["fit"]["fallback"]``).
    drop_outliers : bool
        Leave out the poses far off the fit (named in ``extra["outliers"]`` either way, with
        the fit's change without them).
    min_static_s : float
        Poses found by the static detector: the shortest still stretch taken for a pose
        where a motion touches it (seconds; default 1, a pause in a hand's movement being
        none; a robot arm that stops 0.75 s at each pose: 0.7).

    Returns
    -------
    Calibration
        Offsets (counts), sensitivity vectors (counts per m/s^2), uncertainties and the
        fit's statistics in ``extra["fit"]`` (chi2, dof); what ``accelcal calibrate`` would
        warn of, one line each, in ``extra["warnings"]`` (absent when nothing).

    Examples
    --------
    >>> import accelcal as ac
    >>> dev = ac.default_device()
    >>> rec = ac.simulate(dev, "static_poses", poses="24", seed=1)
    >>> cal = ac.calibrate(dev, rec)
    >>> cal.method
    'full'
    """
    dev = as_device(device)
    cal = calibrate_recordings(dev, _as_recordings(recordings, dev), method=method,
                               jig_accuracy_deg=jig_accuracy_deg, jigfree_model=jigfree_model,
                               drop_outliers=drop_outliers, min_static_s=min_static_s)
    record_warnings(dev, cal)
    return cal


@options_checked()
def resolve(device: Any, calibration: Any, recording: Any, engine: str = "float",
            omega: str = "auto") -> ResolveResult:
    """Per-sample f and alpha (as ``accelcal resolve``).

    Parameters
    ----------
    device : Device, path or "default"
    calibration : Calibration or path
    recording : Recording, path or (n, N) array of raw counts
    engine : {"float", "fixed"}
        ``fixed`` runs the C core with exactly the header's constants.
    omega : {"auto", "reference", "none", "array"}
        Angular rate for the centripetal correction: the recording's w_*, none, the accelerometers'
        own (array); auto: w_* when complete, else array where the layout observes omega.

    Returns
    -------
    ResolveResult
    """
    dev = as_device(device)
    cal = as_calibration(calibration, dev)
    rec = as_recording(recording, dev)
    est = choose_omega_engine(dev, cal, rec, omega, engine)
    f, alpha, flags = resolve_recording(dev, cal, rec, engine, omega, None if est is None else est.for_resolver())
    return ResolveResult(t=rec.t, f=f, alpha=alpha, saturated=flags, clipped=clipped_samples(rec, dev)[0],
                         w=None if est is None else est.w, w_sigma=None if est is None else est.sigma)


@options_checked(_diagnose_impl)
def diagnose(device: Any, calibration: Any, recordings: Any, **options: Any) -> dict:
    """The sim-to-real diagnosis (as ``accelcal diagnose``); returns the JSON object.

    Parameters
    ----------
    device : Device, path or "default"
    calibration : Calibration or path
    recordings : Recording, path, array or a sequence of them
    **options
        ``folds``, ``seed``, ``candidates``, ``progress`` (see ``accelcal.diagnose``).

    Returns
    -------
    dict
        The diagnosis (docs/diagnosis-json.md): ``verdict``, ``effects``, ``model``, ``where``...
    """
    dev = as_device(device)
    return _diagnose_impl(dev, as_calibration(calibration, dev), _as_recordings(recordings, dev), **options)


@options_checked()
def header(device: Any, calibration: Any, *, prefix: str = "AC_CAL", output: Any = None) -> str:
    """The C header for firmware (as ``accelcal header``): the 6-DOF resolver's tables for an
    array, the triad table (f only) for a 3-axis sensor; int16 types for a chip with signed
    output (``raw_min < 0``).

    Parameters
    ----------
    device : Device, path or "default"
    calibration : Calibration or path
    prefix : str
        C identifier prefix.
    output : path, optional
        Also write it there (atomically).

    Returns
    -------
    str
        The header text.
    """
    dev = as_device(device)
    cal = as_calibration(calibration, dev)
    text = calibration_header(dev, cal, prefix=prefix)
    if output is not None:
        atomic_write(output, lambda f: f.write(text))
    return text


@options_checked(_simulate_impl, extra=motion_params)
def simulate(device: Any, motion: str, *, effects: Iterable[Any] = (), seed: int = 0,
             calibration: Any = None, **motion_params: Any) -> Recording:
    """A simulated recording (as ``accelcal simulate``).

    Parameters
    ----------
    device : Device, path or "default"
    motion : str
        Motion profile name (``accelcal simulate --help`` lists them).
    effects : iterable of str
        Effect specs, ``"name:k=v,..."``.
    seed : int
    calibration : Calibration or path, optional
        The true channel parameters (default: the device's nominal ones).
    **motion_params
        The motion's parameters.

    Returns
    -------
    Recording
    """
    dev = as_device(device)
    cal = None if calibration is None else as_calibration(calibration, dev)
    return _simulate_impl(dev, motion, effects=effects, seed=seed, calibration=cal, **motion_params)


def _estimate(fn, device, calibration, recording, engine, options) -> Columns:
    dev = as_device(device)
    return fn(dev, as_calibration(calibration, dev), as_recording(recording, dev), engine, **options)


@options_checked(attitude_from_recording)
def attitude(device: Any, calibration: Any, recording: Any, engine: str = "float", **options: Any) -> Columns:
    """Pendulum attitude from two triads (as ``accelcal attitude``).

    Parameters
    ----------
    device, calibration, recording, engine
        As for :func:`resolve`; two triads (channels 0-2, 3-5) on body x, the pivot at the origin.
    **options
        ``gain`` (1/rad, default 2), ``w2_gate`` ((rad/s)^2 below which ``|w|`` is not measured),
        ``leak_tau_s`` (s, the pull to 0 while ``|w|`` is not measured; default 2), ``omega``
        ("auto", "array", "none": on a 12-channel array that observes omega, theta from f at the
        pivot and w_y the array's own omega, docs/angular-rate.md; "auto" where the layout observes
        it and the recording has no complete w columns).

    Returns
    -------
    Columns
        t (s), theta_rad (rad), w_y (rad/s), dw_y (rad/s^2), g_mps2, gated, unsettled, saturated
        (with the array's omega also w_y_sigma, rad/s).
    """
    return _estimate(attitude_from_recording, device, calibration, recording, engine, options)


@options_checked(displacement_from_recording)
def displacement(device: Any, calibration: Any, recording: Any, engine: str = "float",
                 **options: Any) -> Columns:
    """Stop-to-stop displacement (as ``accelcal displacement``), the velocity zero at each rest.

    Parameters
    ----------
    device, calibration, recording, engine
        As for :func:`resolve` (a 3-axis sensor or an array).
    **options
        ``form`` ("offline" or "stream"; the C core streams), ``axis`` ("x", "y", "z": 1-D along
        it; default 3-D, gravity removed), ``keep_turned``, ``resample``, ``omega`` ("auto", "array",
        "none": f resolved with the centripetal term of the array's own omega; "auto" where the layout
        observes it and the recording has no complete w columns).

    Returns
    -------
    Columns
        t (s), v_* (m/s), p_* (m), p_raw_* (m, uncorrected), rest, corrected.
    """
    return _estimate(displacement_from_recording, device, calibration, recording, engine, options)


@options_checked(rate_from_recording)
def rate(device: Any, calibration: Any, recording: Any, engine: str = "float", **options: Any) -> Columns:
    """Angular rate from alpha, reset on rest (as ``accelcal rate``).

    Parameters
    ----------
    device, calibration, recording, engine
        As for :func:`resolve` (a 6-DOF array).
    **options
        ``leak_tau_s`` (s, the leaky integration's time constant; 0: plain; default 5).

    Returns
    -------
    Columns
        t (s), w_x, w_y, w_z (rad/s), rest.
    """
    return _estimate(rate_from_recording, device, calibration, recording, engine, options)


@options_checked()
def convert(path: Any, fmt: str = "auto", *, units: str | None = None, lsb: float | None = None,
            full_scale_g: float | None = None, bits: int = 16, round: bool = False, rate_hz: float | None = None,
            regions: Any = None, stated_f: bool = False, gravity_mps2: float | None = None, blocks: bool = False,
            time_unit: str = "auto", time_column: str | None = None, columns: str | None = None,
            repeated_stamps: str = "refuse", variable: str | None = None) -> Converted:
    """Another tool's file as a contract recording and a nominal device (as ``accelcal convert``,
    with every option of it: ``--units`` is ``units``, ``--full-scale`` ``full_scale_g``, ``--rate``
    ``rate_hz``, ``--gravity`` ``gravity_mps2``, ``--format`` ``fmt``, the others by their names).

    Parameters
    ----------
    path : str or os.PathLike
        imu_tk's text, imucal's CSV, the MPU-6050 logger's CSV, a contract-like CSV, a
        serial monitor's log, a table with named accelerometer columns, a MATLAB file or an
        Empatica E4's ACC.csv, compressed or not (gzip, bzip2, xz, zstd, a zip of one file).
    fmt : {"auto", "imu_tk", "imucal", "mpu6050", "csv", "log", "table", "mat", "e4"}
        ``auto`` tells it from the file.
    units : {"counts", "mps2", "mmps2", "g", "mg"}, optional
        The unit of the readings in the file; with ``lsb`` (float or str: one count in that
        unit, or with a unit suffix: "1mg") or ``full_scale_g`` (float: +-range in g at ``bits``
        bits).  Default: the file's ``# units:`` / ``# lsb:`` comments or a table's column
        names, else counts; stated by both, they must agree (a contradiction is refused).
    lsb, full_scale_g
        As ``units`` says: one count in that unit, or the +-range in g at ``bits`` bits.
    bits : int
        The ADC's bits (default 16): the device's raw range, and the LSB of ``full_scale_g``.
    round : bool
        Round readings in m/s^2 or g to the nearest LSB (a calibrated logger's floats on no
        LSB's grid), with a note of how far they were; without it such a value is refused.
    rate_hz : float, optional
        Hz, for files without a time column; with a time column, the device's rate where a
        host's time stamps do not give it (t is then put on its grid where the stamps' steps
        disagree by more than 20 %, their long steps noted).  A file of pose means (every row a
        labelled pose of its own) needs none: its t counts the rows (``table.time`` says so).
    regions : path, optional
        JSON of pose regions ``{name: {"start": s, "end": e}}`` (sample numbers, end excluded).
    stated_f : bool
        Poses named ``x_p ... z_a`` get the reference f = +-g along their axis (m/s^2).
    gravity_mps2 : float, optional
        g of the stated f and the device, m/s^2 (default 9.80665; imu_tk 9.81744).
    blocks : bool
        log: each run of readings between the logger's text lines is a pose.
    time_unit : str
        The time column's unit: "s", "ms", "us", "ns", or a tick of a chip's clock, a number
        of one ("25us").  Default "auto": the unit its name states, else seconds, but stamps
        that would be under 2 Hz in seconds are read in the smallest of ms, us, ns that gives
        more (a note says so).  t is written in seconds.
    time_column : str, optional
        table: the time column (default: of the columns named t, time, timestamp, 'Time (s)',
        ..., those holding numbers, the first whose name states a unit, else the first; a
        host's packet stamps give way to a column that times every sample; a note names it).
    columns : str, optional
        table: the accelerometer's three columns, "X,Y,Z", as the header names them (a unit in
        () or [] at a name's end states the readings' unit).
    repeated_stamps : {"refuse", "drop", "shift"}
        table: rows whose time stamp repeats the row before's with other readings are refused
        (the message counts them), left out with a note (``drop``), or, for stamps that
        slipped a place late, moved back a step (``shift``; the other repeats left out).
    variable : str, optional
        mat: the array of readings (3 columns x, y, z, or 4: t, x, y, z) where the file holds
        more than one; or "X,Y,Z" ("T,X,Y,Z"): vectors of one channel each.

    Returns
    -------
    Converted
        ``.recording`` (counts), ``.device`` (a nominal triad), ``.notes``.

    Raises
    ------
    InputError
        One line naming the file, row and column at fault; a value that is not a whole
        number of LSBs is refused with its row.

    Examples
    --------
    >>> c = ac.convert("example_ferraris_session.csv", units="mps2", lsb=9.81 / 2048,
    ...                rate_hz=102.4, regions="example_ferraris_session_list.json",
    ...                stated_f=True, gravity_mps2=9.81)          # doctest: +SKIP
    >>> cal = ac.calibrate(c.device, [c.recording], jig_accuracy_deg=0.5)   # doctest: +SKIP
    """
    scale = stated_scale(units, lsb, full_scale_g, bits, gravity_mps2, round)
    return convert_file(path, fmt, scale=scale, rate_hz=rate_hz, regions=regions, stated_f=stated_f,
                        gravity_mps2=gravity_mps2, bits=bits, blocks=blocks, time_unit=time_unit,
                        variable=variable, time_column=time_column, repeated_stamps=repeated_stamps,
                        columns=columns)
