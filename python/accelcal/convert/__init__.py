"""``accelcal convert``: other tools' files (imu_tk, imucal, loggers, MATLAB, E4, Xsens, ...) read
into the data contract's recording and a nominal device.  :mod:`.formats` is the entry point
(``convert_file``, ``detect_format``); one module per format family or concern beside it."""
