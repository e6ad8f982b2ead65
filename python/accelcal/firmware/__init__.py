"""From a calibration to the C core: the one quantizer (float calibration -> the core's
fixed-point tables), the C header, one triad's firmware path, and the cffi bindings to the
core (:mod:`.native`)."""
