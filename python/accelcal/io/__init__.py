"""The data contract's files and what one count is: devices, calibrations and recordings
(CSV and the other containers), the strict JSON and text readers they share, and units."""
