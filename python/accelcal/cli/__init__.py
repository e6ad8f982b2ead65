"""The ``accelcal`` command: :mod:`.main` (the parser and every subcommand), the calibrate and
convert subcommands' own options and summaries, output paths, and ``accelcal demo``."""
