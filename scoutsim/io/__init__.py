"""A run's files: named tables on disk (:mod:`.tables`, Parquet or gzip-compressed CSV)
and the run directory with its manifest (:mod:`.run_directory`)."""
