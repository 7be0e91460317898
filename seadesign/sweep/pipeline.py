"""The sweep end to end, as `seadesign sweep` runs it: every candidate of a study through the stages
(`sweep.runner`), ranked (`sweep.rank`), the outputs written (`report`), and, with a calibration, the
calibrated study's choice compared with the uncalibrated one's.

Outputs go to ``OUT/<study>/`` (``OUT/<study>-calibrated/`` with a calibration). Lengths in mm where named,
otherwise SI (N, Nm, rad, Pa).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from seadesign.design.materials import Hyperelastic
from seadesign.design.study import DEFAULT_STUDY, Study, load_study
from seadesign.errors import ConfigError
from seadesign.run.cache import default_cache
from seadesign.sweep.rank import Choice, rank
from seadesign.sweep.runner import SweepRun, run_sweep, sweep_settings
from seadesign.sweep.stages import SolverSettings

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.axes import Axes

#: keys a calibration JSON may give, in the order they are looked for
CALIBRATION_KEYS = ("youngs_modulus_fitted_Pa", "youngs_modulus_Pa", "stiffness_scale")


def apply_calibration(study: Study, path: str | Path) -> tuple[Study, str]:
    """The study with a material calibrated from a calibration JSON.

    A file with ``material`` and ``law`` (written by `explain --spring` when the spring's material file is
    found) replaces that material only, in any study, a material axis included: every modulus of its law, and
    its Young's modulus with them, times mu_fitted / mu (mu = 2 (C10 + C01)), so the linear solve and every path
    follow the fitted law. An older file without them gives Young's modulus (``youngs_modulus_fitted_Pa`` or
    ``youngs_modulus_Pa``, Pa) or a bare ``stiffness_scale`` (a factor, right only when it was fitted against
    this study's material) for a study with one material.

    Parameters
    ----------
    study : Study
        The study to calibrate.
    path : str or Path
        The calibration JSON, e.g. ``exports/explain/<file>/<file>_calibration.json``.

    Returns
    -------
    tuple of (Study, str)
        The calibrated study, and a one-line note naming the material, its new mu or E (Pa) and the file.

    Raises
    ------
    ConfigError
        The file is not JSON or lacks the keys, a value is not a positive number, the law's model differs from
        the material's, the study does not use the calibrated material, or (an older file) the study's material
        is a design axis.

    Examples
    --------
    >>> import seadesign as sd
    >>> calibrated, note = sd.apply_calibration(sd.load_study(), "thesis_calibration.json")
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise ConfigError(f"--calibration {path}: cannot be read as JSON ({exc})") from None
    if isinstance(data, dict) and "law" in data and "material" in data:
        return _calibrated_law(study, path, data)
    key = next((k for k in CALIBRATION_KEYS if isinstance(data, dict) and k in data), None)
    if key is None:
        raise ConfigError(f"--calibration {path}: needs 'material' and 'law', or one of {', '.join(CALIBRATION_KEYS)} "
                          "(moduli in Pa, the scale a factor on E); `seadesign explain --spring` writes such a file")
    value = _positive(path, key, data[key])
    if len(study.materials) != 1:
        raise ConfigError(f"--calibration {path}: study '{study.name}' has the material as a design axis and the "
                          "file does not name the material it was fitted to; rerun `seadesign explain --spring` to "
                          "write one that does, or fix the material in the study")
    (name, material), = study.materials.items()
    scale = value if key == "stiffness_scale" else value / material.youngs_modulus_Pa
    note = f"calibrated from {path.name} ({key} = {value:.4g}): E = {material.youngs_modulus_Pa * scale:.4g} Pa"
    return study.with_materials({name: material.scaled(scale, note)}), note


def _positive(path: Path, key: str, value) -> float:
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not value > 0:
        raise ConfigError(f"--calibration {path}: '{key}' must be a positive number, got {value!r}")
    return float(value)


def _calibrated_law(study: Study, path: Path, data: dict) -> tuple[Study, str]:
    """The study with the material the file names given the file's fitted law (see `apply_calibration`)."""
    name, law = data["material"], data["law"]
    if name not in study.materials:
        raise ConfigError(f"--calibration {path}: fitted to material '{name}', which study '{study.name}' does not "
                          f"use (its materials: {', '.join(study.materials)})")
    material = study.materials[name]
    if not isinstance(law, dict):
        raise ConfigError(f"--calibration {path}: 'law' must be a table of the fitted parameters")
    mu = _positive(path, "law/mu_Pa", law.get("mu_Pa"))
    scale = mu / material.law.shear_modulus_Pa
    note = f"calibrated from {path.name}: mu = {mu:.4g} Pa, x {scale:.4g} on every modulus of '{name}'"
    calibrated = material.scaled(scale, note)
    model = law.get("model")
    if model != material.law.model:  # a law of another family (the shape fitted too): its own parameters
        needed = {"mooney_rivlin": ("c10_Pa", "c01_Pa", "d1_per_Pa"), "yeoh": ("c10_Pa", "c20_Pa", "d1_per_Pa"),
                  "neo_hooke": ("c10_Pa", "d1_per_Pa")}.get(model)
        if needed is None:
            raise ConfigError(f"--calibration {path}: law/model '{model}' is unknown; use neo_hooke, mooney_rivlin "
                              f"or yeoh")
        missing = [k for k in needed if not isinstance(law.get(k), (int, float))]
        if missing:
            raise ConfigError(f"--calibration {path}: law/model '{model}' was fitted, but 'law' lacks "
                              f"{', '.join(missing)}; explain the bench file again")
        fields = {k: float(law[k]) for k in ("c10_Pa", "c01_Pa", "c20_Pa", "c30_Pa", "d1_per_Pa", "d2_per_Pa",
                                             "d3_per_Pa") if k in law}
        fitted = Hyperelastic(model, source=note, **fields)
        if abs(fitted.shear_modulus_Pa / mu - 1.0) > 1e-9:
            raise ConfigError(f"--calibration {path}: law/mu_Pa {mu:.6g} is not 2 (C10 + C01) = "
                              f"{fitted.shear_modulus_Pa:.6g} Pa of its own parameters")
        calibrated = replace(calibrated, hyperelastic=fitted)
        note += f" ({model} law: {', '.join(f'{k} {v:.4g}' for k, v in fields.items())})"
    return study.with_materials({name: calibrated}), note


@dataclass
class SweepResult:
    """A finished sweep: the ranked table, the choice, the files written.

    Attributes
    ----------
    study : Study
        The study swept (calibrated when a calibration was given).
    ranked : pandas.DataFrame
        One row per candidate, ranked (columns: ``docs/reference/results.md``, units in the names).
    choice : Choice
        The chosen candidate (``choice.index`` into `ranked`, None when none was solved) and why.
    run : SweepRun
        How the rows were obtained (computed or reused, wall time in s).
    folder : Path
        Where the outputs are.
    written : dict of str to list of Path
        The files written, by kind (tables, plots, report, cad, spring).
    comparison : str or None
        With a calibration: the choice with and without it, and whether each carries the standing load.
    """

    study: Study
    ranked: pd.DataFrame
    choice: Choice
    run: SweepRun
    folder: Path
    written: dict[str, list[Path]]
    comparison: str | None = None

    def lines(self, quiet: bool = False) -> list[str]:
        """What `seadesign sweep` prints when it is done.

        Parameters
        ----------
        quiet : bool
            Leave out the list of files written.

        Returns
        -------
        list of str
            The counts and times, the choice and why, the comparison with the uncalibrated study, the files
            written, and the spring.json verdict.

        Examples
        --------
        >>> print("\\n".join(result.lines(quiet=True)))
        """
        from seadesign.report.verdicts import handoff_verdict

        counts = self.ranked["status"].value_counts().to_dict()
        out = [f"{len(self.ranked)} candidates ({', '.join(f'{n} {k}' for k, n in counts.items())}); "
               f"{len(self.run.computed)} computed, {len(self.run.reused)} reused, {self.run.wall_s:.1f} s",
               self.choice.explanation]
        if self.comparison is not None:
            out.append(self.comparison)
        if not quiet:
            out += [f"wrote {p}" for paths in self.written.values() for p in paths]
        if "spring" in self.written:
            out.append(f"{self.written['spring'][0]}: {handoff_verdict(self.ranked, self.choice)}")
        return out

    def to_frame(self) -> pd.DataFrame:
        """The ranked results table (a copy).

        Returns
        -------
        pandas.DataFrame
            One row per candidate; units in the column names (``k_Nm_per_rad``, ``mass_g``,
            ``large_stop_torque_Nm``, ...), the torque curves in ``large_curve_rotation_rad`` and
            ``large_curve_torque_Nm``.

        Examples
        --------
        >>> result.to_frame()[["candidate", "status", "k_Nm_per_rad"]]
        """
        return self.ranked.copy()

    def plot(self, ax: Axes | None = None) -> Axes:
        """Torque (Nm) against hub rotation (rad) of every solved candidate's path, the chosen one thick, each
        stop marked, the stall and impact torques dashed.

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
        >>> result.plot().figure.savefig("curves.png")
        """
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots(figsize=(7, 5))
        solved = self.ranked[self.ranked["status"] == "ok"]
        for index, row in solved.iterrows():
            chosen = index == self.choice.index
            line, = ax.plot(row["large_curve_rotation_rad"], row["large_curve_torque_Nm"], "-",
                            lw=2.0 if chosen else 0.9, label=f"{row['candidate']}{' (chosen)' if chosen else ''}")
            ax.plot(row["large_stop_rotation_rad"], row["large_stop_torque_Nm"], "x", color=line.get_color())
        lc = self.study.load_cases
        for torque_Nm, name in ((lc.stall_torque_Nm, "stall"), (lc.impact_torque_Nm, "impact")):
            ax.axhline(torque_Nm, color="k", ls="--", lw=0.8)
            ax.annotate(f"{name} {torque_Nm:.3g} Nm", (0, torque_Nm), fontsize=7, xytext=(2, 2),
                        textcoords="offset points")
        ax.set(xlabel="hub rotation (rad)", ylabel="torque (Nm)", title=f"Torque paths of {self.study.name} (x: stop)")
        ax.grid(alpha=0.3)
        if len(solved):
            ax.legend(fontsize=6)
        return ax


def sweep_and_write(study: Study, out_dir: str | Path = Path("exports"), *, baseline: Study | None = None,
                jobs: int | None = None, quiet: bool = False, executor: str = "local", scheduler: str | None = None,
                export_all: bool = False, cache_dir: str | Path | None = None,
                tolerance_mm: float = 0.01, calibration_note: str | None = None) -> SweepResult:
    """Sweep a loaded study (see `sweep_study`); with `baseline`, `study` is its calibrated form, written to
    ``OUT/<study>-calibrated/``, and the baseline is swept too for the comparison.

    Parameters
    ----------
    study : Study
        The study to sweep.
    out_dir : str or Path
        Output root; files go to ``out_dir/<study>/``.
    baseline : Study, optional
        The uncalibrated study `study` was calibrated from (`apply_calibration`).
    jobs, quiet, executor, scheduler, export_all, cache_dir, tolerance_mm
        As in `sweep_study`.
    calibration_note : str, optional
        What the calibration changed (`apply_calibration`'s note), said in the report's Calibration section.

    Returns
    -------
    SweepResult
        The ranked table, the choice and the files written.

    Raises
    ------
    SweepStopped
        A signal stopped it; the finished candidates are saved and a rerun resumes.

    Examples
    --------
    >>> result = sweep_and_write(load_study("wolfgang_knee"), "exports", jobs=2)
    """
    from seadesign.report.sweep_page import Baseline
    from seadesign.report.verdicts import calibration_summary
    from seadesign.sweep.outputs import write_outputs

    cache = default_cache(cache_dir)
    solver = SolverSettings()
    out_dir = Path(out_dir)
    folder = out_dir / (f"{study.name}-calibrated" if baseline is not None else study.name)
    options = dict(settings=solver, cache=cache, executor=executor, jobs=jobs, scheduler=scheduler, quiet=quiet)
    run = run_sweep(study, folder, **options)
    ranked, choice = rank(run.rows, study)
    comparison = compared = None
    if baseline is not None:
        base_ranked, base_choice = rank(run_sweep(baseline, out_dir / baseline.name, **options).rows, baseline)
        comparison = calibration_summary(base_ranked, base_choice, ranked, choice, study)
        compared = Baseline(calibration_note or "the calibration file's material", base_ranked, base_choice)
    written = write_outputs(study, ranked, choice, folder, sweep_settings(study, solver), solver=solver, cache=cache,
                            export_all=export_all, tolerance_mm=tolerance_mm, baseline=compared)
    return SweepResult(study, ranked, choice, run, folder, written, comparison)


def sweep_study(study: str | Path | Study = DEFAULT_STUDY.stem, out_dir: str | Path = Path("exports"), *,
          calibration: str | Path | None = None, jobs: int | None = None, quiet: bool = False,
          executor: str = "local", scheduler: str | None = None, export_all: bool = False,
          cache_dir: str | Path | None = None, tolerance_mm: float = 0.01) -> SweepResult:
    """Run every candidate of a study (geometry, validity, mesh, both linear load cases, the large-deflection
    torque path), rank them on their paths and write the results, plots, report, STL/STEP and spring.json,
    as `seadesign sweep`. Resumable: stored rows and cached stages are reused.

    Parameters
    ----------
    study : str, Path or Study
        A study name (``NAME.toml`` here, else the packaged one), a path, or a loaded study.
    out_dir : str or Path
        Output root; files go to ``out_dir/<study>/``.
    calibration : str or Path, optional
        Calibration JSON (from `explain`) whose fitted modulus replaces the material's Young's modulus;
        outputs go to ``out_dir/<study>-calibrated/`` and the uncalibrated study is swept for the comparison.
    jobs : int, optional
        Worker processes (count); None: all cores.
    quiet : bool
        No progress display.
    executor : {"local", "dask"}
        A local process pool, or a Dask distributed cluster.
    scheduler : str, optional
        Dask scheduler address ``HOST:PORT``; a LocalCluster of `jobs` workers when None.
    export_all : bool
        STL and STEP (mm) of every valid candidate, not only the chosen one.
    cache_dir : str or Path, optional
        Stage cache folder; None: $SEADESIGN_CACHE, else ~/.cache/seadesign.
    tolerance_mm : float
        STL chordal tolerance (mm).

    Returns
    -------
    SweepResult
        The ranked table (``to_frame()``), the torque paths (``plot()``), the choice and the files written.

    Raises
    ------
    ConfigError
        The study or the calibration file is invalid (the message names the key).
    SweepStopped
        A signal stopped it; the finished candidates are saved and a rerun resumes.

    Examples
    --------
    >>> import seadesign as sd
    >>> result = sd.sweep_study("wolfgang_knee", jobs=2, quiet=True)
    >>> result.plot()
    """
    study = study if isinstance(study, Study) else load_study(study)
    baseline = None
    if calibration is not None:
        baseline = study
        study, note = apply_calibration(study, calibration)
    return sweep_and_write(study, out_dir, baseline=baseline, jobs=jobs, quiet=quiet, executor=executor,
                           scheduler=scheduler, export_all=export_all, cache_dir=cache_dir, tolerance_mm=tolerance_mm,
                           calibration_note=note if baseline is not None else None)

