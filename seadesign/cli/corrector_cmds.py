"""`seadesign train` and `seadesign evaluate`: the corrector's command line."""

from __future__ import annotations

import click

from seadesign.cli import main
from seadesign.corrector.dataset import TASKS
from seadesign.corrector.models import MODEL_KINDS
from seadesign.corrector.pipeline import CAPS_S, TRAIN_KINDS, iterate_training
from seadesign.corrector.pipeline import evaluate as evaluate_correctors
from seadesign.corrector.pipeline import train as train_correctors
from seadesign.corrector.splits import SPLITS
from seadesign.corrector.train import TrainConfig
from seadesign.corrector.workflow import DEFAULT_HISTORY, PREVIEW_MODELS
from seadesign.design.spring import load_spring


def _models(text: str) -> list[str]:
    models = [m.strip() for m in text.split(",") if m.strip()]
    bad = [m for m in models if m not in TRAIN_KINDS]
    if bad or not models:
        raise click.BadParameter(f"unknown model(s) {bad}; choose from {', '.join(TRAIN_KINDS)} (comma-separated)")
    return models


@main.command()
@click.option("--spring", "spring_path", required=True, type=click.Path(dir_okay=False),
              help="spring.json from `seadesign sweep` (k is read from it; the file must pass its schema)")
@click.option("--data", "data", multiple=True, type=click.Path(exists=True, dir_okay=False),
              help="robot recording CSV (repeat for several files); trains the models on recordings; for 'closedloop' "
                   "and 'reference' it checks their simulator against the robot (k and effects, by the loop)")
@click.option("--model", "model_text", default="closedloop", show_default=True,
              help=f"one or more of {', '.join(TRAIN_KINDS)}, comma-separated. closedloop (the one that wins in "
                   "closed loop): the reference network below, fine-tuned through the closed loop in the knee "
                   "simulator with a feedback on the Hall error whose gain is bounded (0.5 rad/rad). reference: "
                   "feed-forward from the walk engine's trajectory, trained on iterative-learning-control labels "
                   "in the knee simulator. Both are trained over k x0.8-1.25 and read no recorded state")
@click.option("--modalities", default="velocity_effort", show_default=True,
              help="a thesis combination name (target_only, velocity_effort, all, ...) or a comma-separated "
                   "list of motor_pos, hall_pos, motor_vel, hall_vel, effort, imu, pressure")
@click.option("--task", type=click.Choice(TASKS), default="thesis", show_default=True,
              help="thesis: target = Hall position at t; inverse: target = Hall position at t+1")
@click.option("--positive/--normal", default=True, show_default=True,
              help="mirror the right knee so both knees look alike (thesis 'positive' dataset)")
@click.option("--history", type=int, default=None,
              help=f"past samples as extra inputs (default 0; {DEFAULT_HISTORY} for the history model)")
@click.option("--split", "split_name", type=click.Choice(SPLITS), default="time_blocks", show_default=True)
@click.option("--test-recording", multiple=True, help="recording name(s) held out by --split by_recording")
@click.option("--seed", type=int, default=0, show_default=True)
@click.option("--max-epochs", type=int, default=TrainConfig.max_epochs, show_default=True)
@click.option("--patience", type=int, default=TrainConfig.patience, show_default=True, help="epochs")
@click.option("--max-seconds", type=float, default=None,
              help="wall-clock cap per model, s [default: 60 for a network on recordings, 600 for the reference, "
                   "300 for the closed loop; inf: none]")
@click.option("--batch-size", type=int, default=TrainConfig.batch_size, show_default=True)
@click.option("--lr", type=float, default=TrainConfig.lr, show_default=True, help="Adam learning rate")
@click.option("-o", "--out", "out", type=click.Path(file_okay=False), default=None,
              help="bundle folder (several models: one subfolder each); default exports/<study>/corrector/")
def train(spring_path: str, data: tuple[str, ...], model_text: str, modalities: str, task: str, positive: bool,
          history: int | None, split_name: str, test_recording: tuple[str, ...], seed: int, max_epochs: int,
          patience: int, max_seconds: float | None, batch_size: int, lr: float, out: str | None) -> None:
    """Train corrector network(s) and export bundles (TorchScript, ONNX, NumPy): by default the closed-loop corrector
    trained in the knee simulator built from spring.json; models on recordings with --model."""
    models = _models(model_text)
    load_spring(spring_path)  # a bad spring.json is named before a missing --data
    if not data and [m for m in models if m not in PREVIEW_MODELS]:
        raise click.BadParameter("models trained on recordings need --data FILE (repeat for several files)")
    train_correctors(spring_path, tuple(models), data, modalities=modalities, task=task, positive=positive,
                     history=history, split=split_name, test_recording=test_recording, seed=seed,
                     max_epochs=max_epochs, patience=patience, max_seconds=max_seconds, batch_size=batch_size, lr=lr,
                     out=out, echo=click.echo)


@main.command()
@click.argument("bundles", nargs=-1, required=True, type=click.Path(exists=True, file_okay=False))
@click.option("--data", "data", multiple=True, type=click.Path(exists=True, dir_okay=False),
              help="recording CSV(s) for the open-loop table; training files contribute only their held-out rows "
                   "(without: closed loop only)")
@click.option("--json", "json_path", type=click.Path(dir_okay=False), default=None, help="also write results as JSON")
@click.option("-o", "--out", "out", type=click.Path(file_okay=False), default=None,
              help="output folder; default exports/<study>/corrector/evaluation")
@click.option("--kp", type=float, default=0.2, show_default=True, help="PI baseline proportional gain")
@click.option("--ki", type=float, default=0.1, show_default=True, help="PI baseline integral gain, 1/s")
@click.option("--closed-loop", "closed_loop", default="hanging,ground", show_default=True,
              help="simulator settings for the closed-loop table (comma-separated; 'none' to skip)")
@click.option("--trial-s", type=float, default=10.0, show_default=True, help="closed-loop trial duration, s")
def evaluate(bundles: tuple[str, ...], data: tuple[str, ...], json_path: str | None, out: str | None,
             kp: float, ki: float, closed_loop: str, trial_s: float) -> None:
    """Score corrector bundles against the baselines, open loop on recordings and closed loop in the
    knee simulator; write tables (CSV, Markdown[, JSON]) and plots."""
    settings = tuple(s.strip() for s in closed_loop.split(",") if s.strip() and s.strip() != "none")
    res = evaluate_correctors(bundles, data, out=out, json_path=json_path, kp=kp, ki=ki, closed_loop=settings,
                              trial_s=trial_s)
    both = [r for r in res.get("open_loop", []) if r["knee"] == "both"]
    if both:
        click.echo(f"open loop ({res['settings']['rows']}):")
    for r in both:
        click.echo(f"  {r['candidate']:<45} MAE {r['mae_rad']:.4f} rad  MSE {r['mse_rad2']:.4g} rad^2  "
                   f"peak {r['peak_rad']:.3f} rad")
    for r in res.get("closed_loop", []):
        if "mean_abs_error_rad" in r:
            flags = ", ".join(f for f in ("unstable", "oscillating", "loop_gain") if r.get(f"{f}_flag"))
            click.echo(f"  closed loop {r['setting']:<8} {r['candidate']:<45} mean |Hall error| "
                       f"{r['mean_abs_error_rad']:.4f} rad  peak {r['peak_abs_error_rad']:.3f} rad  "
                       f"margin {r['modulus_margin']:.2f}  {'stable' if r['stable'] else 'NOT stable: ' + flags}")
    for f in res["files"]:
        click.echo(f"wrote {f}")


@main.command()
@click.option("--spring", "spring_path", required=True, type=click.Path(dir_okay=False), help="spring.json")
@click.option("--data", "data", multiple=True, type=click.Path(exists=True, dir_okay=False),
              help="starting recordings (none: start from a simulated run without correction)")
@click.option("--model", type=click.Choice(MODEL_KINDS), default="mlp", show_default=True)
@click.option("--modalities", default="velocity_effort", show_default=True)
@click.option("--task", type=click.Choice(TASKS), default="command", show_default=True)
@click.option("--positive/--normal", default=True, show_default=True)
@click.option("--history", type=int, default=None, help=f"past samples (default 0; {DEFAULT_HISTORY} for history)")
@click.option("--rounds", type=int, default=2, show_default=True, help="retraining rounds after round 0")
@click.option("--setting", type=click.Choice(["hanging", "ground"]), default="hanging", show_default=True)
@click.option("--trial-s", type=float, default=10.0, show_default=True, help="trial duration, s")
@click.option("--seed", type=int, default=0, show_default=True)
@click.option("--max-seconds", type=float, default=CAPS_S["network"], show_default=True,
              help="wall-clock cap per round, s")
@click.option("-o", "--out", "out", type=click.Path(file_okay=False), default=None,
              help="output folder; default exports/<study>/corrector/iterative")
def iterate(spring_path: str, data: tuple[str, ...], model: str, modalities: str, task: str, positive: bool,
            history: int | None, rounds: int, setting: str, trial_s: float, seed: int, max_seconds: float,
            out: str | None) -> None:
    """Iterative training: retrain on simulator runs recorded with the current corrector in the loop."""
    table, files = iterate_training(spring_path, data, model=model, modalities=modalities, task=task,
                                    positive=positive, history=history, rounds=rounds, setting=setting,
                                    trial_s=trial_s, seed=seed, max_seconds=max_seconds, out=out)
    for r in table.to_dict("records"):
        click.echo(f"round {r['round']}: mean |Hall error| {r['mean_abs_error_rad']:.4f} rad, peak "
                   f"{r['peak_abs_error_rad']:.3f} rad, unstable {r['unstable_flag']}, "
                   f"oscillating {r['oscillating_flag']}")
    click.echo(f"wrote {files['csv']} and {files['md']}")
