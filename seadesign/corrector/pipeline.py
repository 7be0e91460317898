"""The corrector's pipelines as `seadesign train`, `evaluate` and `iterate` run them: one or more models trained
and exported as bundles, bundles scored against the baselines, and iterative retraining on simulator runs.

Angles in rad, time in s, torques in Nm.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Callable

import pandas as pd

from seadesign.corrector.closedloop_training import FINE_TUNING
from seadesign.corrector.dataset import DatasetSpec
from seadesign.corrector.export import versions
from seadesign.corrector.imitation import ImitationSettings
from seadesign.corrector.iterative import iterate as run_iterations
from seadesign.corrector.models import MODEL_KINDS
from seadesign.corrector.preflight import check_spring_range
from seadesign.corrector.recordings import load_recordings
from seadesign.corrector.report import write_table
from seadesign.corrector.simcheck import SimulatorCheck, check_simulator
from seadesign.corrector.train import TrainConfig
from seadesign.corrector.workflow import (DEFAULT_HISTORY, PREVIEW_MODELS, candidate_name, evaluate_bundles,
                                          train_bundle, train_closedloop_bundle, train_reference_bundle)
from seadesign.design.spring import load_spring
from seadesign.errors import ConfigError
from seadesign.twin import thesis_protocol

#: every model `train` knows: the preview models trained in the knee simulator, then those trained on recordings
TRAIN_KINDS = (*PREVIEW_MODELS, *MODEL_KINDS)
#: `train`'s wall-clock cap per model (s) by kind when none is given: a network on recordings, the reference
#: network on ILC labels (also as the closed loop's start), the closed-loop fine-tuning
CAPS_S = {"network": 60.0, "reference": 600.0, "closedloop": 300.0}


def capped_reference_settings(max_seconds: float) -> ImitationSettings:
    """The reference network's default settings with its training capped at `max_seconds` (s)."""
    settings = ImitationSettings()
    return replace(settings, train=replace(settings.train, max_seconds=max_seconds))


@dataclass(frozen=True)
class TrainedCorrector:
    """One trained and exported corrector.

    Attributes
    ----------
    name : str
        The model's name (the model kind, with its dataset spec for models trained on recordings).
    bundle : Path
        The bundle folder (TorchScript, ONNX, NumPy and meta.json).
    summary : str
        How the training went (best validation error with its unit, epoch, stop, wall time in s).
    """

    name: str
    bundle: Path
    summary: str

    def line(self) -> str:
        """The line `seadesign train` prints for it.

        Returns
        -------
        str
            ``NAME: SUMMARY -> BUNDLE``.

        Examples
        --------
        >>> TrainedCorrector("mlp", Path("b"), "best validation MSE 0.01 rad^2").line()
        'mlp: best validation MSE 0.01 rad^2 -> b'
        """
        return f"{self.name}: {self.summary} -> {self.bundle}"


def simulator_check_lines(checks: list[SimulatorCheck]) -> list[str]:
    """The simulator check's lines, and a warning when the robot's k is outside the tested range.

    Parameters
    ----------
    checks : list of SimulatorCheck
        The check of the knee simulator against each recording (`corrector.simcheck.check_simulator`).

    Returns
    -------
    list of str
        One line per check (``WARNING:`` first when out of range), then the advice to calibrate if any is.

    Examples
    --------
    >>> simulator_check_lines([])
    []
    """
    out = [("" if c.within_robust_range else "WARNING: ") + "simulator check: " + c.text() for c in checks]
    if any(not c.within_robust_range for c in checks):
        out.append("WARNING: the robot's k is outside what this corrector was tested for; calibrate "
                   "spring.json first (seadesign explain, then sweep --calibration)")
    return out


def train(spring: str | Path, models: str | tuple[str, ...] = "closedloop", data: tuple[str | Path, ...] = (), *,
          modalities: str = "velocity_effort", task: str = "thesis", positive: bool = True, history: int | None = None,
          split: str = "time_blocks", test_recording: tuple[str, ...] = (), seed: int = 0,
          max_epochs: int = TrainConfig.max_epochs, patience: int = TrainConfig.patience,
          max_seconds: float | None = None, batch_size: int = TrainConfig.batch_size,
          lr: float = TrainConfig.lr, out: str | Path | None = None,
          echo: Callable[[str], None] | None = None) -> list[TrainedCorrector]:
    """Train corrector network(s) and export each as a bundle (TorchScript, ONNX, NumPy), as `seadesign train`:
    by default the closed-loop corrector trained in the knee simulator built from spring.json.

    Parameters
    ----------
    spring : str or Path
        spring.json from the sweep (k in Nm/rad is read from it; it must pass its schema).
    models : str or tuple of str
        One or more of ``closedloop`` (reference network fine-tuned through the closed loop), ``reference``
        (feed-forward on iterative-learning-control labels) and the networks trained on recordings
        (``seadesign.corrector.MODEL_KINDS``).
    data : tuple of str or Path
        Robot recording CSVs: the training data of the models trained on recordings; for the preview models
        the recordings their simulator is checked against.
    modalities : str
        Inputs of the models trained on recordings: a thesis combination name or a comma-separated list.
    task : {"thesis", "inverse"}
        Target: the Hall position at t, or at t+1.
    positive : bool
        Mirror the right knee so both knees look alike.
    history : int, optional
        Past samples as extra inputs (count); None: 0, or 3 for the history model.
    split : str
        How rows are split into training and validation (``seadesign.corrector.SPLITS``).
    test_recording : tuple of str
        Recording names held out by the ``by_recording`` split.
    seed : int
        Seed of the split and the training.
    max_epochs, patience : int
        Epoch cap and early-stopping patience (epochs).
    max_seconds : float, optional
        Wall-clock cap per model (s); None: each kind's `CAPS_S`.
    batch_size : int
        Samples per step.
    lr : float
        Adam learning rate.
    out : str or Path, optional
        Bundle folder (several models: one subfolder each); None: ``exports/<study>/corrector/``.
    echo : callable, optional
        Receives each line as it is known (the simulator check, then each model's summary); the CLI prints them.

    Returns
    -------
    list of TrainedCorrector
        Each model's name, bundle folder and training summary, in training order (the reference first: the
        closed-loop model fine-tunes it).

    Raises
    ------
    ConfigError
        An unknown model, or models trained on recordings without `data`.
    SpringFileError
        spring.json cannot be read or fails its schema, or its curve ends before the protocol's loads.

    Examples
    --------
    >>> import seadesign as sd
    >>> [c.bundle for c in sd.train("exports/wolfgang_knee/spring.json")]
    """
    echo = echo or (lambda line: None)
    models = [m.strip() for m in models.split(",")] if isinstance(models, str) else list(models)
    bad = [m for m in models if m not in TRAIN_KINDS]
    if bad or not models:
        raise ConfigError(f"models: unknown model(s) {bad}; choose from {', '.join(TRAIN_KINDS)}")
    doc = load_spring(spring)
    on_data = [m for m in models if m not in PREVIEW_MODELS]
    if not data and on_data:
        raise ConfigError(f"models {', '.join(on_data)} are trained on recordings and need data (recording CSVs)")
    data = [str(d) for d in data]
    recs = load_recordings(data) if on_data else []  # the preview models' simulator check reads the files
    caps = CAPS_S if max_seconds is None else dict.fromkeys(CAPS_S, max_seconds)
    cfg = TrainConfig(seed=seed, max_epochs=max_epochs, patience=patience, max_seconds=caps["network"],
                      batch_size=batch_size, lr=lr)
    root = Path(out) if out else Path("exports") / doc["study"] / "corrector"
    preview = set(models) & set(PREVIEW_MODELS)
    if preview:
        check_spring_range(doc)  # refuses here, before any training, a curve that ends before the protocol's loads
    checks = check_simulator(doc, data) if preview else []
    for line in simulator_check_lines(checks):
        echo(line)
    trained, imitation = [], None
    for model in sorted(models, key=lambda m: m != "reference"):  # reference first: closedloop fine-tunes it
        if model in PREVIEW_MODELS:
            reference = capped_reference_settings(caps["reference"])
            folder = {"reference": "reference-ilc", "closedloop": "closedloop"}[model]
            target = root if (out and len(models) == 1) else root / folder
            if model == "reference":
                path, imitation, _ = train_reference_bundle(spring, target, reference, data_paths=data,
                                                          checks=checks)
                s = imitation.summary()["training"]
                summary = (f"ILC labels {imitation.label_s:.0f} s ({len(imitation.labels)} batches); best validation "
                           f"MSE "
                           f"{s['best_val_mse_rad2']:.4g} rad^2 at epoch {s['best_epoch']} ({s['stopped']}, "
                           f"{s['wall_s']:.1f} s)")
            else:
                fine_tuning = replace(FINE_TUNING, max_seconds=caps["closedloop"])
                path, res, _ = train_closedloop_bundle(spring, target, fine_tuning, imitation=imitation,
                                                       data_paths=data, checks=checks, imitation_settings=reference)
                s = res.summary()
                summary = (f"fine-tuned through the closed loop: validation mean |Hall error| "
                           f"{s['best_val_mean_abs_error_rad']:.4f} rad at epoch {s['best_epoch']} ({s['stopped']}, "
                           f"{s['wall_s']:.1f} s); feedback gain bound {s['feedback_lipschitz_bound_rad_per_rad']:.3f} "
                           "rad/rad")
            trained.append(TrainedCorrector(model, Path(path), summary))
        else:
            h = history if history is not None else (DEFAULT_HISTORY if model == "history" else 0)
            spec = DatasetSpec(task, modalities, h, positive)
            name = candidate_name(model, spec)
            target = root if (out and len(models) == 1) else root / name
            path, res = train_bundle(spring, data, model, spec, split, cfg, target, list(test_recording) or None,
                                     recordings=recs)
            s = res.summary()
            trained.append(TrainedCorrector(name, Path(path), (
                f"best validation MSE {s['best_val_mse_rad2']:.4g} rad^2 at epoch {s['best_epoch']} ({s['stopped']}, "
                f"{s['wall_s']:.1f} s, {s['samples_per_s']:.0f} samples/s)")))
        echo(trained[-1].line())
    return trained


def evaluate(bundles: tuple[str | Path, ...], data: tuple[str | Path, ...] = (), *, out: str | Path | None = None,
             json_path: str | Path | None = None, kp: float = 0.2, ki: float = 0.1,
             closed_loop: tuple[str, ...] = ("hanging", "ground"), trial_s: float = 10.0) -> dict[str, Any]:
    """Score corrector bundles against the baselines, open loop on recordings and closed loop in the knee
    simulator, and write the tables (CSV, Markdown[, JSON]) and plots, as `seadesign evaluate`.

    Parameters
    ----------
    bundles : tuple of str or Path
        Bundle folders, or folders holding bundles.
    data : tuple of str or Path
        Recording CSVs for the open-loop table; training files contribute only their held-out rows (none:
        closed loop only).
    out : str or Path, optional
        Output folder; None: ``exports/<study>/corrector/evaluation``.
    json_path : str or Path, optional
        Also write the results as JSON here.
    kp : float
        PI baseline proportional gain (rad/rad).
    ki : float
        PI baseline integral gain (1/s).
    closed_loop : tuple of str
        Simulator settings of the closed-loop table (``hanging``, ``ground``); empty: no closed loop.
    trial_s : float
        Closed-loop trial duration (s).

    Returns
    -------
    dict
        ``open_loop`` and ``closed_loop`` rows (errors in rad, stability flags and margins), ``settings`` and
        the ``files`` written.

    Raises
    ------
    SeadesignError
        A folder holds no bundle, or a bundle cannot be read (named).

    Examples
    --------
    >>> import seadesign as sd
    >>> rows = sd.evaluate(["exports/wolfgang_knee/corrector"])["closed_loop"]
    """
    return evaluate_bundles(list(bundles), list(data), out, json_path, kp, ki, tuple(closed_loop), trial_s)


def iterate_training(spring: str | Path, data: tuple[str | Path, ...] = (), *, model: str = "mlp",
                     modalities: str = "velocity_effort", task: str = "command", positive: bool = True,
                     history: int | None = None, rounds: int = 2, setting: str = "hanging", trial_s: float = 10.0,
                     seed: int = 0, max_seconds: float = CAPS_S["network"],
                     out: str | Path | None = None) -> tuple[pd.DataFrame, dict[str, Path]]:
    """Iterative training, as `seadesign iterate`: retrain on simulator runs recorded with the current corrector
    in the loop, and write the table of rounds.

    Parameters
    ----------
    spring : str or Path
        spring.json the knee simulator is built from.
    data : tuple of str or Path
        Starting recordings; none: start from a simulated run without correction.
    model : str
        The network (``seadesign.corrector.MODEL_KINDS``).
    modalities : str
        Inputs: a thesis combination name or a comma-separated list.
    task : str
        The dataset task (``seadesign.corrector.dataset.TASKS``).
    positive : bool
        Mirror the right knee so both knees look alike.
    history : int, optional
        Past samples as extra inputs (count); None: 0, or 3 for the history model.
    rounds : int
        Retraining rounds after round 0 (count).
    setting : {"hanging", "ground"}
        The simulator setting the runs are recorded in.
    trial_s : float
        Trial duration (s).
    seed : int
        Seed of the training and the simulator.
    max_seconds : float
        Wall-clock cap per round (s).
    out : str or Path, optional
        Output folder; None: ``exports/<study>/corrector/iterative``.

    Returns
    -------
    tuple of (pandas.DataFrame, dict of str to Path)
        One row per round (``mean_abs_error_rad``, ``peak_abs_error_rad``, flags), and the CSV and Markdown
        files written.

    Raises
    ------
    SpringFileError
        spring.json cannot be read or fails its schema.

    Examples
    --------
    >>> table, files = iterate_training("exports/wolfgang_knee/spring.json", rounds=1)
    """
    doc = load_spring(spring)
    h = history if history is not None else (DEFAULT_HISTORY if model == "history" else 0)
    spec = DatasetSpec(task, modalities, h, positive)
    cfg = TrainConfig(model=model, seed=seed, max_seconds=max_seconds)
    table, _ = run_iterations(doc, load_recordings([str(d) for d in data]), spec, cfg, rounds, setting,
                              thesis_protocol(trial_s), seed=seed)
    folder = Path(out) if out else Path("exports") / doc["study"] / "corrector" / "iterative"
    files = write_table(table, folder, "iterative", {"spec": spec.to_dict(), "training": cfg.__dict__,
                                                    "setting": setting, "trial_s": trial_s,
                                                    "data": [str(Path(d).resolve()) for d in data],
                                                    "versions": versions()})
    return table, files
