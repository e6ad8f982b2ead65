"""Sim-to-real diagnosis: where the gap between recordings and a calibrated model lies,
which effect of the data contract causes it, and how far it shrinks once the effect is added.

    result = diagnose(device, calibration, recordings)   # the contract's JSON object
    write_report(result, "report/")                       # plots and a summary

The method and the JSON format are documented in docs/diagnosis-json.md.  Modules:
``inputs`` (coercion), ``prepare`` (the model's prediction and the data to fit),
``floor`` (noise floor), ``scoring`` (held-out gain and significance), ``compare`` (can
the data tell the verdict from its rivals), ``relinearise`` (the joint fit about the
corrected calibration), ``leftover`` (what is left: ``unexplained``), ``settling`` (a
ringing after the stops), ``where`` (the breakdown), ``text`` (JSON entries and prose),
``stepping`` (one step of the search: rivals the data cannot tell apart, the calibration's
terms against a verdict that mimics them, the next step's point), ``result`` (the stepwise
search and the verdict).  Each effect's own fit lives with the effect (:mod:`accelcal.effects`).
"""
from ..report import write_report
from .result import DiagnosisResult, diagnose
from .settings import FORMAT, MAX_STEPS, MIN_SHRINK, PENALTY_PER_PARAM, T_MIN, Z_MIN

__all__ = ["diagnose", "write_report", "DiagnosisResult", "FORMAT", "T_MIN", "Z_MIN", "PENALTY_PER_PARAM",
           "MIN_SHRINK", "MAX_STEPS"]
