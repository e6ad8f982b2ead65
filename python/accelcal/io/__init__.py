"""The data contract's files and what one count is: devices, calibrations and recordings
(CSV and the other containers, Parquet: parquet), the strict JSON and text readers they share, and units;
recordings read in chunks (chunks)."""
