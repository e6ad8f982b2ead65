"""Guided capture from a live sensor: stillness, pose capture, refit, the next pose by
information, until the uncertainty target (``accelcal capture``; docs/capture.md).

Modules: ``source`` (the port, standard input or a file replayed; lines parsed, bad ones
counted), ``loop`` (stillness by the static detector, pose capture, jig-free refit),
``plan`` (the next orientation by the minimax criterion, and its words), ``events`` (the
JSON lines of ``--json`` and the human text).
"""
from .events import Events
from .loop import CaptureLoop
from .plan import next_direction, words
from .source import LineSource, PortLost, parse_line

__all__ = ["CaptureLoop", "Events", "LineSource", "PortLost", "next_direction", "parse_line", "words"]
