"""Execution machinery shared by the sweep and the explorer: the stage cache, executors (serial,
process pool, Dask), the progress display."""
