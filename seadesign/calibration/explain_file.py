"""A measured file explained end to end, as `seadesign explain FILE` does it: a bench file or a robot recording
against the model a spring.json makes, or any table with a measured and a predicted column; the declared model
refitted, missing effects traced, the report and the calibration JSON written."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import pandas as pd

from seadesign.data import clean, is_hanging, read_bench, read_recording
from seadesign.design.spring import load_spring
from seadesign.errors import ConfigError
from seadesign.calibration.engine import Explanation, explain
from seadesign.calibration.law_family import FAMILIES, bench_shapes
from seadesign.calibration.report import write_report
from seadesign.calibration.sea import ROBOT_DECLARED, bench_loop_data, calibration, robot_declared, robot_loop_data
from seadesign.calibration.table import ROLES, LoopData, from_frame

if TYPE_CHECKING:
    from matplotlib.axes import Axes


@dataclass
class FileExplanation:
    """What `explain_file` found and wrote.

    Attributes
    ----------
    explanation : Explanation
        The steps: the declared model refitted (``plain``), each effect added, the final model (``final``),
        with errors on the training and held-out rows.
    data : LoopData
        The measured and predicted signals the loop worked on (``data.measured_unit``).
    calibration : dict or None
        The calibration (fitted k in Nm/rad, fitted Young's modulus in Pa, ...) for bench and robot files.
    files : dict of str to Path
        The report's files by kind (md, html, json, calibration, plots).
    """

    explanation: Explanation
    data: LoopData
    calibration: dict | None
    files: dict[str, Path] = field(default_factory=dict)

    def lines(self) -> list[str]:
        """What `seadesign explain` prints.

        Returns
        -------
        list of str
            The verdict, the RMSE before and after (the measured unit), each declared effect's check, each
            effect found with its parameters (value +- uncertainty, unit), the files written.

        Examples
        --------
        >>> print("\\n".join(found.lines()))
        """
        ex = self.explanation
        e0, e1 = ex.plain.errors, ex.final.errors
        out = [ex.verdict(),
               f"RMSE ({self.data.measured_unit}) train {e0['train']['rmse']:.4g} -> {e1['train']['rmse']:.4g}, "
               f"held-out {e0['held_out']['rmse']:.4g} -> {e1['held_out']['rmse']:.4g}"]
        out += [f"  declared {check.text()}" for check in ex.declared]
        for key in ex.added:
            ps = ex.final.parameters().get(key, {})
            out.append(f"  found {key}: " + ", ".join(f"{n} = {p['value']:.4g} +- {p['uncertainty']:.2g} {p['unit']}"
                                                      for n, p in ps.items()))
        out += [f"{kind}: {path}" for kind, path in self.files.items()]
        return out

    def to_frame(self) -> pd.DataFrame:
        """The errors of the declared model refitted and after each effect added, per part of the data.

        Returns
        -------
        pandas.DataFrame
            Columns ``step`` ("declared model", then "+ EFFECT"), ``part`` (train, held_out) and the error
            measures (``rmse`` and the others of `loop.metrics`, in the measured unit).

        Examples
        --------
        >>> found.to_frame().query("part == 'held_out'")
        """
        fits = [("declared model", self.explanation.plain)]
        fits += [(f"+ {step.effect}", step.after) for step in self.explanation.steps]
        return pd.DataFrame([{"step": name, "part": part, **errors} for name, fit in fits
                             for part, errors in fit.errors.items()])

    def plot(self, ax: Axes | None = None) -> Axes:
        """Held-out RMSE (the measured unit) after each step of the loop.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Where to draw; None: a new figure.

        Returns
        -------
        matplotlib.axes.Axes
            The axes drawn on.

        Examples
        --------
        >>> found.plot().figure.savefig("steps.png")
        """
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots(figsize=(6, 4))
        t = self.to_frame()
        held = t[t["part"] == "held_out"]
        ax.plot(range(len(held)), held["rmse"], "o-")
        ax.set_xticks(range(len(held)), held["step"], rotation=20, ha="right", fontsize=7)
        ax.set(ylabel=f"held-out RMSE ({self.data.measured_unit})", title="Error after each step of the loop")
        ax.grid(alpha=0.3)
        return ax


def _kind(path: Path) -> str:
    header = pd.read_csv(path, nrows=0).columns
    if "l_hall_pos" in header:
        return "robot"
    if "torque_Nm" in header and "deflection_rad" in header:
        return "bench"
    raise ConfigError(f"{path}: neither a bench file (time_s, torque_Nm, deflection_rad) nor a robot recording "
                      "(l_hall_pos, ...); for another table give --measured, --predicted and --signal")


def explain_file(file: str | Path, spring: str | Path | None = None, *, out_dir: str | Path | None = None,
                 json_out: str | Path | None = None, predict: str = "torque", knee: str = "l",
                 keep_lifted: bool | None = None, measured: str | None = None, predicted: str | None = None,
                 signals: dict[str, str] | None = None, units: dict[str, str] | None = None,
                 measured_unit: str = "1", declare: tuple[str, ...] = (), plain: bool = False,
                 min_gain: float = 0.05, law: str = "auto") -> FileExplanation:
    """Explain the residual between a model and a measured file: the declared model refitted, missing effects
    traced, the error before and after, as `seadesign explain FILE`; writes the report and, for bench and
    robot files, the calibration JSON that `sweep_study(calibration=...)` reads.

    Parameters
    ----------
    file : str or Path
        A bench file (``time_s``, ``torque_Nm``, ``deflection_rad``) or a robot recording (with `spring`), or
        any CSV table (with `measured`, `predicted` and `signals`).
    spring : str or Path, optional
        spring.json whose k (Nm/rad) and material make the model; needed for bench and robot files.
    out_dir : str or Path, optional
        Folder for the report, plots and calibration JSON; None: ``exports/explain/<file stem>``.
    json_out : str or Path, optional
        Also copy the JSON report here.
    predict : {"torque", "deflection"}
        Bench files: predict torque (Nm) from deflection, or deflection (rad) from torque.
    knee : {"l", "r"}
        Robot recordings: which knee (the right is un-mirrored).
    keep_lifted : bool, optional
        Robot recordings: keep rows whose foot pressure sum is low; None keeps them only in a hanging recording.
    measured, predicted : str, optional
        Generic table: the measured column and the model's prediction (same unit).
    signals : dict of str to str, optional
        Generic table: role -> column (roles: ``seadesign.calibration.ROLES``).
    units : dict of str to str, optional
        Generic table: role -> unit, for the report.
    measured_unit : str
        Generic table: the unit of `measured`.
    declare : tuple of str
        Robot files: the declared effects to refit (default: dead band and friction); generic tables: effects
        the prediction already holds (not traced).
    plain : bool
        Robot files: declare nothing but the spring (k refitted).
    min_gain : float
        Relative held-out RMSE cut (fraction, 0-1) an effect needs to be added.
    law : {"auto", "scale", "mooney_rivlin", "yeoh"}
        Bench files predicting torque, with a spring.json that has a torque curve: the material law's shape traced
        beside the scale (``auto``: Mooney-Rivlin and Yeoh; each needs the spring's study, to recompute its part's
        path for trial laws), or the scale alone (``scale``).

    Returns
    -------
    FileExplanation
        The explanation (``to_frame()``, ``plot()``, ``lines()``), the calibration and the files written.

    Raises
    ------
    ConfigError
        A generic table without both columns, a bench or robot file without `spring`, an unknown signal
        role, or a file of neither kind (each named).
    SpringFileError, DataError
        spring.json or the measured file cannot be read (named).
    SpringSourceError
        The law's shape is asked for, but spring.json's study cannot be loaded or no longer gives its curve.

    Examples
    --------
    >>> import seadesign as sd
    >>> found = sd.explain("bench.csv", spring="exports/wolfgang_knee/spring.json")
    >>> found.calibration["k_fitted_Nm_per_rad"]
    """
    file = Path(file)
    if law not in ("auto", "scale", *FAMILIES):
        raise ConfigError(f"law = '{law}': use auto, scale, {', '.join(FAMILIES)}")
    spring_doc, declared, exclude = None, [], ()
    if measured or predicted:
        if not (measured and predicted):
            raise ConfigError("a generic table needs both --measured and --predicted")
        unknown = sorted(set(signals or {}) - set(ROLES))
        if unknown:
            raise ConfigError(f"signals: unknown role(s) {', '.join(unknown)}; roles: {', '.join(ROLES)}")
        data = from_frame(pd.read_csv(file), measured, predicted, dict(signals or {}), units=dict(units or {}),
                          measured_unit=measured_unit)
        exclude, loop_plot, stem = tuple(declare), False, file.stem
    else:
        if spring is None:
            raise ConfigError(f"{file}: bench and robot files need --spring PATH (spring.json with k)")
        spring_doc = load_spring(spring)
        if _kind(file) == "bench":
            data = bench_loop_data(read_bench(file), spring_doc, predict)
            if law != "scale" and predict == "torque" and "torque_curve" in spring_doc:
                bench_shapes(spring_doc, data, tuple(FAMILIES) if law == "auto" else (law,))
            loop_plot, stem = True, file.stem
        else:
            raw = read_recording(file)
            keep = is_hanging(raw) if keep_lifted is None else keep_lifted
            table = clean(raw, keep_lifted=keep, normalise=False, euler=False).table
            data = robot_loop_data(table, spring_doc, knee)
            declared = [] if plain else robot_declared(spring_doc, tuple(declare) or tuple(ROBOT_DECLARED))
            loop_plot, stem = False, f"{file.stem}_{knee}"
    out_dir = Path(out_dir) if out_dir else Path("exports") / "explain" / stem
    ex = explain(data, declared, exclude=exclude, min_gain=min_gain)
    cal = calibration(ex, spring_doc, file) if spring_doc is not None else None
    files = write_report(ex, out_dir, stem, f"Explain {file.name}", loop_plot=loop_plot, calibration=cal)
    if json_out is not None:
        json_out = Path(json_out)
        json_out.parent.mkdir(parents=True, exist_ok=True)
        json_out.write_text(files["json"].read_text())
    return FileExplanation(ex, data, cal, files)
