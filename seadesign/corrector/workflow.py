"""Train-and-export and evaluate-bundles workflows behind the CLI (`seadesign train`, `seadesign evaluate`).

A trained corrector is a bundle directory (see `export.py`); its meta.json records the spring
(k and where it came from), the data files (SHA-256), the dataset spec, split, training settings
and outcome, and versions, so every number can be traced back.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from seadesign.corrector.closedloop import closed_loop_table
from seadesign.corrector.dataset import KNEES, CorrectorDataset, DatasetSpec, Recording, build_dataset
from seadesign.corrector.evaluate import open_loop_table
from seadesign.corrector.closedloop_policy import MEASURED_INPUTS, RATE_TIME_S, FlatPolicy, policy_arrays
from seadesign.corrector.closedloop_training import FINE_TUNING, ClosedLoopResult, ClosedLoopSettings, train_closed_loop
from seadesign.corrector.export import export_bundle, input_list, load_meta, load_numpy, normalisation, versions
from seadesign.corrector.modalities import COMBINATIONS
from seadesign.corrector.recordings import load_recordings
from seadesign.corrector.report import plot_curves, plot_predictions, write_table
from seadesign.corrector.imitation import ImitationResult, ImitationSettings, train_imitation
from seadesign.corrector.reference import ReferenceWindow
from seadesign.corrector.runtime import (ClosedLoopCorrector, Corrector, FeedForward, HallPI, NetCorrector, NoCorrection,
                                         ReferenceFeedForward)
from seadesign.corrector.simcheck import SimulatorCheck, check_simulator
from seadesign.corrector.stability import MIN_MODULUS_MARGIN, loop_gain_table
from seadesign.corrector.splits import Split, make_split
from seadesign.corrector.train import TrainConfig, TrainResult, fit
from seadesign.errors import SeadesignError
from seadesign.design.spring import TorqueCurve, load_spring, torque_curve
from seadesign.twin import KneeConfig, knee_effects, thesis_protocol

DEFAULT_HISTORY = 3  # samples, for the history model when no --history is given
#: models driven from the walk engine's preview (reference window), trained in the knee simulator (recordings only
#: check it) and not scored open loop on recordings; the first is the default of `seadesign train`
PREVIEW_MODELS = ("closedloop", "reference")


def candidate_name(model: str, spec: DatasetSpec) -> str:
    """Readable name: model, normal/positive, modalities (combination name when one matches), history."""
    mods = next((k for k, v in COMBINATIONS.items() if v == spec.modalities), "+".join(spec.modalities))
    hist = f"-h{spec.history}" if spec.history else ""
    return f"{model}-{'positive' if spec.positive else 'normal'}-{mods}{hist}-{spec.task}"


def file_digest(path: str | Path) -> str:
    """SHA-256 of a file's bytes."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def data_record(paths: list[str | Path]) -> list[dict[str, str]]:
    """Name, absolute path and SHA-256 of each data file."""
    return [{"name": Path(p).stem, "path": str(Path(p).resolve()), "sha256": file_digest(p)} for p in paths]


def train_bundle(spring_path: str | Path, data_paths: list[str | Path], model: str, spec: DatasetSpec,
                 split_name: str, config: TrainConfig, out_dir: str | Path,
                 test_recordings: list[str] | None = None,
                 recordings: list[Recording] | None = None) -> tuple[Path, TrainResult]:
    """Train one corrector on recording files and export it as a bundle into `out_dir`.

    The spring file is validated first (SpringFileError when it fails its schema); k comes from it.
    `recordings` may be given already loaded (same order as `data_paths`).
    """
    spring = load_spring(spring_path)
    k = float(spring["k_Nm_per_rad"])
    recs = recordings if recordings is not None else load_recordings(data_paths)
    ds = build_dataset(recs, spec)
    split = make_split(ds, split_name, seed=config.seed, test_recordings=test_recordings)
    result = fit(ds, split, k, TrainConfig(**{**config.__dict__, "model": model}))
    meta = {
        "name": candidate_name(model, spec), "model": model, "dataset": spec.to_dict(),
        "inputs": input_list(ds.feature_names, model == "siamese"),
        "output": "motor position command at t+1, rad (robot frame after un-mirroring)",
        "positive_note": "right-knee inputs and output are sign-flipped" if spec.positive else "",
        "k_Nm_per_rad": k,
        "spring": {"path": str(Path(spring_path).resolve()), "study": spring["study"], "k_source": spring["k_source"],
                   "inputs_hash": spring["inputs_hash"]},
        "data": data_record(data_paths), "n_samples": len(ds), "split": split.describe(),
        "training": result.summary(),
    }
    out = export_bundle(result.net, meta, out_dir)
    pd.DataFrame(result.curve).to_csv(out / "training_curve.csv", index=False)
    return out, result


def _spring_record(spring_path: str | Path, spring: dict[str, Any]) -> dict[str, Any]:
    return {"path": str(Path(spring_path).resolve()), "study": spring["study"], "k_source": spring["k_source"],
            "inputs_hash": spring["inputs_hash"]}


def _simulator_record(spring: dict[str, Any], conditions: tuple[str, ...], k_scales: tuple[float, ...]) -> dict[str, Any]:
    """The knee simulator a preview corrector was trained in: config, conditions (hanging, ground), effect chains,
    k scales (1)."""
    config = KneeConfig.from_spring(spring)
    return {"config": config.as_dict(), "conditions": list(conditions), "k_scales": list(k_scales),
            "effects": {c: knee_effects(config, c == "ground").describe() for c in conditions}}


def train_reference_bundle(spring_path: str | Path, out_dir: str | Path,
                           settings: ImitationSettings = ImitationSettings(), data_paths: list[str | Path] = (),
                           checks: list[SimulatorCheck] | None = None,
                           ) -> tuple[Path, ImitationResult, list[SimulatorCheck]]:
    """The reference network: ILC labels in the simulator built from spring.json, the reference-window network
    trained on them, exported as a bundle whose meta records the window, k, the simulator and the control rate. The
    recordings in `data_paths`, if any, check that simulator (`simcheck.check_simulator`, unless its `checks`
    are given; in meta)."""
    spring = load_spring(spring_path)
    checks = check_simulator(spring, list(data_paths)) if checks is None else checks
    result = train_imitation(spring, settings)
    meta = {
        "name": "reference-ilc", "model": "reference", "reference": settings.window.to_dict(),
        "inputs": list(settings.window.feature_names()),
        "output": "motor position command at t, rad, knee flexion (mirror the right knee in and out)",
        "k_Nm_per_rad": float(spring["k_Nm_per_rad"]), "spring": _spring_record(spring_path, spring),
        "control_rate_hz": settings.rate_hz,
        "simulator": _simulator_record(spring, settings.conditions, settings.k_scales),
        "data": data_record(list(data_paths)), "simulator_check": [c.to_dict() for c in checks],
        "n_samples": int(sum(r.target_rad.size for r in result.labels)),
        "split": {"split": "held_out_trials", "val_every": settings.val_every},
        "training": result.summary(),
    }
    out = export_bundle(result.training.net, meta, out_dir)
    pd.DataFrame(result.training.curve).to_csv(out / "training_curve.csv", index=False)
    return out, result, checks


def train_closedloop_bundle(spring_path: str | Path, out_dir: str | Path, settings: ClosedLoopSettings = FINE_TUNING,
                            imitation: ImitationResult | None = None, data_paths: list[str | Path] = (),
                            checks: list[SimulatorCheck] | None = None,
                            imitation_settings: ImitationSettings = ImitationSettings(),
                            ) -> tuple[Path, ClosedLoopResult, list[SimulatorCheck]]:
    """The closed-loop policy, the default corrector: the reference network `imitation` (trained here with
    `imitation_settings` when None) fine-tuned through the closed loop in the torch knee built from spring.json,
    exported by `export_closedloop_bundle`; meta records the reference network's training under "init". The
    recordings in `data_paths`, if any, check that simulator (`simcheck.check_simulator`, unless its `checks` are
    given; in meta)."""
    spring = load_spring(spring_path)
    checks = check_simulator(spring, list(data_paths)) if checks is None else checks
    imitation = train_imitation(spring, imitation_settings) if imitation is None else imitation
    result = train_closed_loop(spring, settings, imitation.training.net)
    meta = {"data": data_record(list(data_paths)), "simulator_check": [c.to_dict() for c in checks],
            "init": {"imitation": imitation.summary()}}
    return export_closedloop_bundle(result, spring_path, out_dir, meta), result, checks


def export_closedloop_bundle(result: ClosedLoopResult, spring_path: str | Path, out_dir: str | Path,
                             record: dict[str, Any] | None = None, name: str = "closedloop") -> Path:
    """A closed-loop bundle named `name`: flat input the reference window then `MEASURED_INPUTS`; meta records the
    window, k, the feedback's certified bound, the simulator, control rate and training, plus `record`'s fields."""
    spring = load_spring(spring_path)
    policy, settings = result.policy, result.settings
    meta = {
        "name": name, "model": "closedloop", "reference": settings.window.to_dict(),
        "inputs": [*settings.window.feature_names(), *MEASURED_INPUTS],
        "measured_inputs": f"{MEASURED_INPUTS[0]} = target - hall; {MEASURED_INPUTS[1]} = {RATE_TIME_S:g} s x "
                           "(target's finite difference / dt - hall velocity); flexion (mirror the right knee)",
        "output": "motor position command at t, rad, knee flexion (mirror the right knee in and out)",
        "k_Nm_per_rad": float(spring["k_Nm_per_rad"]), "spring": _spring_record(spring_path, spring),
        "control_rate_hz": settings.rate_hz, "rate_time_s": RATE_TIME_S,
        "feedback_lipschitz_bound_rad_per_rad": policy.feedback_lipschitz_bound(),
        "normalisation": {**normalisation(policy.ff), "applies_to": "the reference window; the measured inputs "
                          "enter the feedback in rad, unscaled"},
        "simulator": _simulator_record(spring, settings.conditions, settings.k_scales),
        "split": {"split": "held_out_speeds", "val_speeds_m_per_s": list(settings.val_speeds)},
        **(record or {}), "training": result.summary(),
    }
    out = export_bundle(FlatPolicy(policy), meta, out_dir, arrays=policy_arrays(policy))
    pd.DataFrame(result.curve).to_csv(out / "training_curve.csv", index=False)
    return out


def find_bundles(paths: list[str | Path]) -> list[Path]:
    """Bundle directories among `paths` (a bundle itself, or a folder holding bundles)."""
    found: list[Path] = []
    for p in map(Path, paths):
        if (p / "meta.json").exists():
            found.append(p)
        elif p.is_dir():
            found.extend(sorted(d for d in p.iterdir() if (d / "meta.json").exists()))
    if not found:
        raise SeadesignError(f"no corrector bundle (folder with meta.json) in {', '.join(map(str, paths))}; "
                             "create one with `seadesign train`")
    return found


def load_corrector(bundle: str | Path) -> tuple[Corrector, dict[str, Any]]:
    """A bundle as an online corrector (NumPy path) plus its meta."""
    meta = load_meta(bundle)
    if meta["model"] in PREVIEW_MODELS:
        kind = ReferenceFeedForward if meta["model"] == "reference" else ClosedLoopCorrector
        return kind(load_numpy(bundle), ReferenceWindow(**meta["reference"]), meta["k_Nm_per_rad"],
                    name=meta["name"]), meta
    spec = DatasetSpec.from_dict(meta["dataset"])
    return NetCorrector(load_numpy(bundle), spec, meta["name"]), meta


def evaluation_rows(meta: dict, data_paths: list[str | Path], recs: list[Recording]) -> tuple[CorrectorDataset, Split, str]:
    """The dataset of the reference bundle on `data_paths` and the rows to score.

    Files the bundle was trained on contribute only the held-out rows of its own split (rebuilt
    with the same settings); files it never saw contribute every row.
    """
    spec = DatasetSpec.from_dict(meta["dataset"])
    ds = build_dataset(recs, spec)
    trained = {r["sha256"] for r in meta["data"]}
    seen = np.array([file_digest(p) in trained for p in data_paths])
    unseen_rows = np.flatnonzero(~seen[ds.recording])
    if seen.all() and len(seen) == len(trained):
        sp = meta["split"]
        split = make_split(ds, sp["split"], seed=sp["seed"], test_recordings=sp.get("test_recordings"))
        return ds, split, f"{split.name} held-out rows of the training files"
    if not seen.any():
        return ds, Split("unseen_recordings", np.array([], int), np.array([], int), np.arange(len(ds))), \
            "recordings not used in training (all rows)"
    return ds, Split("unseen_recordings", np.array([], int), np.array([], int), unseen_rows), \
        "rows of the recordings not used in training"


def _curve_exceeded(curve: TorqueCurve | None, recs: list[Recording]) -> str:
    """Why the curve-based feed-forward cannot score `recs` (their largest |effort| past the curve's end, which is
    not extrapolated), or "" when it can."""
    if curve is None or curve.hard_stop:
        return ""
    effort = max(float(np.nanmax(np.abs(r.knees[k]["effort_Nm"]))) for r in recs for k in KNEES)
    if effort <= curve.end_torque_Nm:
        return ""
    return (f"the recordings' efforts reach {effort:.4g} Nm, and the spring's torque curve ends at "
            f"{curve.end_rotation_rad:.4g} rad, {curve.end_torque_Nm:.4g} Nm (stop reason {curve.stop_reason}; it is "
            "not extrapolated)")


def evaluate_bundles(bundle_paths: list[str | Path], data_paths: list[str | Path], out_dir: str | Path | None = None,
                     json_path: str | Path | None = None, kp: float = 0.2, ki: float = 0.1,
                     closed_loop: tuple[str, ...] = ("hanging", "ground"), trial_s: float = 10.0,
                     seed: int = 0) -> dict[str, Any]:
    """Open-loop table of all bundles vs the baselines (none, PI, feed-forward), plots and settings;
    then, for each setting in `closed_loop`, the closed-loop table in the knee simulator (thesis
    protocol, `trial_s` s per trial) built from the spring.json the first bundle was trained with.

    Rows scored open loop: see `evaluation_rows` (decided by the first bundle that reads measurements;
    the reference-window family reads none and is not scored there). The closed-loop table carries each
    corrector's loop-gain margins (`stability.measure_loop_gain`) and a `stable` verdict. Default output
    folder: exports/<study>/corrector/evaluation.
    """
    bundles = find_bundles(bundle_paths)
    nets = [load_corrector(b) for b in bundles]
    k = float(nets[0][1]["k_Nm_per_rad"])
    spring_meta = nets[0][1]["spring"]
    out = Path(out_dir) if out_dir else Path("exports") / spring_meta["study"] / "corrector" / "evaluation"
    spring_file = Path(spring_meta["path"])
    spring = load_spring(spring_file) if spring_file.exists() else None
    curve = torque_curve(spring) if spring is not None else None
    feed_forward = (f"the torque curve of {spring_file}" if curve is not None else
                    f"k = {k:g} Nm/rad" + ("" if spring is not None else f" ({spring_file} not found)"))
    correctors: list[Corrector] = [NoCorrection(), HallPI(kp, ki), FeedForward(k, curve)] + [c for c, _ in nets]
    measured = [(b, c, m) for b, (c, m) in zip(bundles, nets) if m["model"] not in PREVIEW_MODELS]
    context = {"reference_bundle": str(bundles[0]), "data": data_record(data_paths),
               "k_Nm_per_rad": k, "feed_forward_spring": feed_forward, "pi": {"kp": kp, "ki": ki}, "versions": versions(),
               "candidates": {m["name"]: {"bundle": str(b), "training": m["training"], "split": m["split"]}
                              for b, (_, m) in zip(bundles, nets)},
               "not_judged_open_loop": [m["name"] for _, m in nets if m["model"] in PREVIEW_MODELS]}
    result: dict[str, Any] = {"settings": context, "files": []}
    if measured and data_paths:  # the preview families need the walk engine's trajectory: nothing to score on recordings
        recs = load_recordings(data_paths)
        ds, split, context["rows"] = evaluation_rows(measured[0][2], data_paths, recs)
        ol = [c for c in correctors if not getattr(c, "preview_steps", 0)]
        beyond = _curve_exceeded(curve, recs)
        if beyond:  # the curve-based feed-forward cannot follow these efforts: not scored, and said why
            ol = [c for c in ol if not isinstance(c, FeedForward)]
            context["not_judged_open_loop"].append("feedforward")
            context["feedforward_not_judged"] = beyond
        table, traces = open_loop_table(ol, recs, ds, split.test, split.name)
        files = write_table(table, out, "open_loop", context)
        plots = [plot_predictions(traces, out / "predictions_left.png", knee=0),
                 plot_predictions(traces, out / "predictions_right.png", knee=1)]
        result["open_loop"] = table.to_dict("records")
        result["files"] += [str(p) for p in [*files.values(), *plots]]
    out.mkdir(parents=True, exist_ok=True)
    curves = plot_curves({m["name"]: pd.read_csv(b / "training_curve.csv").to_dict("records")
                          for b, (_, m) in zip(bundles, nets)}, out / "training_curves.png")
    result["files"].append(str(curves))
    if closed_loop:
        spring = load_spring(spring_file)  # a clear error when it is gone: the simulator needs it
        trials = thesis_protocol(trial_s)
        cl_table, _ = closed_loop_table(correctors, spring, closed_loop, trials, seed=seed)
        gains = loop_gain_table(correctors, spring, closed_loop, trials, seed=seed)
        cl_table = cl_table.merge(gains, on=["candidate", "setting"], how="left")
        cl_table["stable"] = ~(cl_table.unstable_flag.astype(bool) | cl_table.oscillating_flag.astype(bool)
                               | cl_table.loop_gain_flag.astype(bool))
        cl_context = {"protocol": f"thesis: 6 directions x 3 speeds, {trial_s:g} s each", "seed": seed,
                      "spring": spring_meta, "versions": versions(),
                      "stability": f"stable = no unstable or oscillating flag and a loop-gain modulus margin >= "
                                   f"{MIN_MODULUS_MARGIN:g} with crossover gain <= {MIN_MODULUS_MARGIN:g} "
                                   "(seadesign.corrector.stability)"}
        cl_files = write_table(cl_table, out, "closed_loop", cl_context)
        result["closed_loop"] = cl_table.to_dict("records")
        result["closed_loop_settings"] = cl_context
        result["files"] += [str(p) for p in cl_files.values()]
    if json_path:
        Path(json_path).parent.mkdir(parents=True, exist_ok=True)
        Path(json_path).write_text(json.dumps(result, indent=2, default=str) + "\n")
    return result
