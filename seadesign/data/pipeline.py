"""`seadesign data inspect` and `seadesign data clean` as functions, for ``import seadesign as sd``: a robot
recording's file in, its artefact report (with the plot on request) or its cleaned table out. The caller
writes (`RecordingInspection.plot`, `seadesign.data.write_cleaned`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from seadesign.data.artefacts import ArtefactReport, Thresholds, detect_artefacts
from seadesign.data.cleaning import CleanResult, clean
from seadesign.data.robot import read_recording


@dataclass(frozen=True)
class RecordingInspection:
    """A recording and the artefacts found in it, per knee."""

    frame: pd.DataFrame = field(repr=False)  # the recording as `read_recording` gives it
    report: ArtefactReport

    def plot(self, path: str | Path) -> Path:
        """Write the inspection plot (PNG): per knee motor and Hall with the artefacts marked, the deflection,
        and the sample interval with gaps. Returns the path written."""
        from seadesign.data.plots import plot_recording

        return plot_recording(self.frame, self.report, path)


def inspect_recording(path: str | Path, thresholds: Thresholds = Thresholds()) -> RecordingInspection:
    """Read a robot recording and find its artefacts: gaps, Hall wrap-arounds, steps, glitches, stuck segments
    and the Hall offset at rest, per knee.

    Parameters
    ----------
    path : str or Path
        The recording (robot format, see the data formats reference).
    thresholds : Thresholds
        Detection settings (rad, s, Nm; as `--step-threshold` and `--gap-factor`).

    Returns
    -------
    RecordingInspection
        The recording and its report (``report.format()``, ``report.to_dict()``, ``plot(path)``).

    Raises
    ------
    DataError
        The file is malformed; the message names line, row and column.

    Examples
    --------
    >>> import seadesign as sd
    >>> inspection = sd.inspect_recording("ground_dtest_part1.csv")
    >>> print(inspection.report.format())
    >>> inspection.plot("ground_inspect.png")
    """
    frame = read_recording(path)
    return RecordingInspection(frame, detect_artefacts(frame, thresholds))


def clean_recording(path: str | Path, *, pressure_threshold: float = 10.0, keep_lifted: bool = False,
                    drop_artefacts: bool = True, unwrap: bool = True, remove_offset: bool = True,
                    normalise: bool = True, positive: bool = False) -> CleanResult:
    """Read a robot recording and clean it as the thesis did, logging every step and removed row.

    Parameters
    ----------
    path : str or Path
        The recording (robot format).
    pressure_threshold : float
        Rows whose summed foot pressure (8 cells, the robot's cell units, about N) is below this are dropped as
        lifted.
    keep_lifted : bool
        Keep lifted rows (hanging recordings).
    drop_artefacts : bool
        Drop rows with glitches and stuck Hall values.
    unwrap, remove_offset : bool
        Undo Hall wrap-arounds; remove the Hall offset found at rest.
    normalise : bool
        Positions in rad/pi (the thesis's unit) instead of rad.
    positive : bool
        Mirror the right knee onto the left (the thesis's "positive" dataset).

    Returns
    -------
    CleanResult
        The cleaned table, the step log and the removed rows per reason (``format()``); write it with
        `seadesign.data.write_cleaned`.

    Raises
    ------
    DataError
        The file is malformed, or every row is lifted and `keep_lifted` is off.

    Examples
    --------
    >>> import seadesign as sd
    >>> from seadesign.data import write_cleaned
    >>> result = sd.clean_recording("ground_dtest_part1.csv", positive=True)
    >>> write_cleaned(result, "ground_clean.csv", "ground_dtest_part1.csv")
    """
    return clean(read_recording(path), pressure_threshold=pressure_threshold, keep_lifted=keep_lifted,
                 drop_artefacts=drop_artefacts, unwrap=unwrap, remove_offset=remove_offset, normalise=normalise,
                 positive=positive)
