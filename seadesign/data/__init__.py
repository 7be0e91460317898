"""Measured data: the robot recording and bench formats, artefact detection and cleaning.

Public API (stable):

- `read_recording(path) -> DataFrame`, `write_recording(df, path, metadata=None)`: the
  robot format (`robot.py`, columns in `RECORDING_COLUMNS`); `knee_channels(df, knee)`: one knee's
  channels as signals of the one vocabulary (`FIELD_SIGNALS`: motor, hall, motor_velocity,
  hall_velocity, effort; flexion convention), knee sides `l`/`r` and names `left`/`right` (`KNEE_NAMES`).
- `read_bench(path) -> DataFrame`, `write_bench(df, path, metadata=None)`: the bench format
  `time_s, torque_Nm, deflection_rad[, temperature_C]` (`bench.py`).
- `read_metadata(csv_path)`, `write_metadata(csv_path, dict)`: the `<name>.meta.json` sidecar.
- `detect_artefacts(df) -> ArtefactReport` (`artefacts.py`).
- `clean(df, ...) -> CleanResult` with the cleaned table and the step log (`cleaning.py`);
  `write_cleaned(result, path)` writes it flat with a sidecar (log, removed rows, units).
- `plot_recording(df, report, path)`: the inspection plot (`plots.py`).
- `inspect_recording(path)`, `clean_recording(path, ...)`: `data inspect` and `data clean` from a file
  (`pipeline.py`, imported from there: it is the API's layer, `sd.inspect_recording`).

Every malformed input raises `seadesign.errors.DataError` naming line, row and column.
"""

from seadesign.data.artefacts import ArtefactReport, Thresholds, detect_artefacts
from seadesign.data.bench import BENCH_OPTIONAL, BENCH_REQUIRED, read_bench, write_bench
from seadesign.data.cleaning import CleanResult, clean, is_hanging, quaternion_to_euler, write_cleaned
from seadesign.data.metadata import read_metadata, sidecar_path, write_metadata
from seadesign.data.plots import plot_recording
from seadesign.data.robot import (
    FIELD_SIGNALS,
    KNEE_NAMES,
    KNEE_SIGN_BY_NAME,
    KNEE_SIGN,
    KNEES,
    RECORDING_COLUMNS,
    KneeChannels,
    knee_channels,
    read_recording,
    write_recording,
)

__all__ = [
    "ArtefactReport", "CleanResult", "plot_recording", "Thresholds", "clean", "detect_artefacts", "is_hanging", "quaternion_to_euler", "write_cleaned",
    "BENCH_OPTIONAL", "BENCH_REQUIRED", "FIELD_SIGNALS", "KNEES", "KNEE_NAMES", "KNEE_SIGN", "KNEE_SIGN_BY_NAME", "KneeChannels",
    "RECORDING_COLUMNS", "knee_channels",
    "read_bench", "read_metadata", "read_recording", "sidecar_path", "write_bench",
    "write_metadata", "write_recording",
]
