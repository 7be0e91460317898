"""Closed-loop policy training benchmark: the corrector trained through the closed loop in the torch knee, from
scratch and fine-tuning the reference network (the default of `seadesign train`), with the bundles for the comparison.

Trains the reference network (`train_reference_bundle`: ILC labels, then the network), the closed-loop policy
fine-tuning it (the default, `train_closedloop_bundle`) and the closed-loop policy from scratch, and writes the three
bundles into --out. Prints per run the wall time to its stop rule (the closed-loop policy, `closedloop_training`: the
validation trials' mean |Hall error| not 1 % below its best for `patience` epochs; the reference network:
`benchmarks/train_reference.py`), the epochs, the simulated steps per
second (one step = one 10 ms sample of the whole batch: training and validation trials x hanging/ground x k scales
x 2 knees; the no-gradient passes and the BPTT windows together, and the BPTT windows alone), and the NumPy
runtime's latency per control step (median), the default bundle's single-call latency on each path (ONNX Runtime,
NumPy, TorchScript; 1 thread), then the default's wall time (the reference network + fine-tuning). Compare the bundles
with

    python benchmarks/closed_loop_goal.py OUT/reference-ilc OUT/closedloop-scratch OUT/closedloop --spring SPRING

    python benchmarks/train_closedloop.py [--spring studies/thesis_measured_spring.json] [--out DIR] [--threads 1]
        [--docs]

`--docs` writes the runs' table into docs/validation/_fragments/closedloop_training.md.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import torch

from seadesign import __version__
from seadesign.corrector.closedloop_policy import runtime_corrector
from seadesign.corrector.closedloop_training import FINE_TUNING, ClosedLoopResult, ClosedLoopSettings, train_closed_loop
from seadesign.corrector.export import load_meta, load_numpy, load_torchscript
from seadesign.corrector.pipeline import CAPS_S, capped_reference_settings
from seadesign.corrector.reference import Preview
from seadesign.corrector.runtime import STEP_BUDGET_US
from seadesign.corrector.workflow import export_closedloop_bundle, train_closedloop_bundle, train_reference_bundle
from seadesign.design.spring import load_spring
from seadesign.onnx_corrector import load_onnx
from record import Table, add_docs_option, machine, write_fragment

THESIS_SPRING = Path(__file__).resolve().parents[1] / "studies" / "thesis_measured_spring.json"


def _median_us(fn, calls: int) -> float:
    """Median wall time of one call of `fn` (us), after 200 warm-up calls."""
    for _ in range(200):
        fn()
    times = np.empty(calls)
    for i in range(calls):
        t0 = time.perf_counter()
        fn()
        times[i] = time.perf_counter() - t0
    return float(np.median(times) * 1e6)


def _step_us(corrector, calls: int) -> float:
    """Median wall time of one online `command` call (us): walking target, left knee."""
    preview = Preview(np.linspace(1.0, 1.1, corrector.preview_steps), np.full(corrector.preview_steps + 1, 0.5))
    measured = {"hall_pos_rad": 0.98, "hall_vel_rad_per_s": 0.2}
    corrector.reset()
    return _median_us(lambda: corrector.command("left", 1.0, measured, 0.01, preview), calls)


def _paths_us(bundle: Path, calls: int) -> dict[str, float]:
    """Median single-call latency (us) of the bundle's flat forward on each path (1 torch thread)."""
    z = np.zeros(len(load_meta(bundle)["inputs"]), dtype=np.float32)
    npc, onnx, ts = load_numpy(bundle), load_onnx(bundle), load_torchscript(bundle)
    before = torch.get_num_threads()
    torch.set_num_threads(1)
    with torch.inference_mode():
        zt = torch.from_numpy(z[None, :])
        ts_us = _median_us(lambda: ts(zt), calls)
    torch.set_num_threads(before)
    return {"onnx": _median_us(lambda: onnx(z), calls), "numpy": _median_us(lambda: npc(z), calls), "torchscript": ts_us}


COLUMNS = ["run", "learning rate", "epochs", "best epoch", "stop", "wall time (s)", "simulated batch steps/s",
           "BPTT steps/s", "validation mean abs Hall error (rad)", "feedback bound (rad/rad)", "control step (us)"]


def _row(name: str, res: ClosedLoopResult, k: float, calls: int) -> list[str]:
    """The run's cells, in COLUMNS's order."""
    bptt_s = sum(row["bptt_s"] for row in res.curve)
    step_us = _step_us(runtime_corrector(res.policy, k), calls)
    return [name, f"{res.settings.lr:g}", f"{len(res.curve) - 1}", f"{res.best_epoch}", res.stopped, f"{res.wall_s:.1f}",
            f"{res.simulated_steps / res.wall_s:.0f}", f"{res.trained_steps / bptt_s:.0f}",
            f"{res.curve[res.best_epoch]['val_mean_abs_error_rad']:.4f}", f"{res.policy.feedback_lipschitz_bound():.3f}",
            f"{step_us:.1f}"]


def _print(cells: list[str]) -> None:
    print(f"{cells[0]:<22} " + " ".join(f"{c:>10}" for c in cells[1:]), flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spring", type=Path, default=THESIS_SPRING)
    ap.add_argument("--out", type=Path, default=Path("exports") / "benchmark_closedloop", help="bundles go here")
    ap.add_argument("--threads", type=int, default=1, help="torch intra-op threads for closed-loop training")
    ap.add_argument("--calls", type=int, default=3000, help="runtime latency: command calls timed")
    add_docs_option(ap, "closedloop_training")
    args = ap.parse_args()
    spring = load_spring(args.spring)
    k = spring["k_Nm_per_rad"]
    base = ClosedLoopSettings(threads=args.threads, max_seconds=CAPS_S["closedloop"])  # as `seadesign train`
    knees = (len(base.directions) * (len(base.speeds) + len(base.val_speeds)) * len(base.conditions)
             * len(base.k_scales) * 2)
    print(f"machine: {machine()}; torch {torch.__version__}, seadesign {__version__}; spring {args.spring} "
          f"(k {k:.4g} Nm/rad)")
    settings = (f"The closed-loop policy: {len(base.directions)} directions x speeds {base.speeds} (training) and "
                f"{base.val_speeds} "
                f"(validation), {base.trial_s:g} s trials, {' and '.join(base.conditions)}, k x {base.k_scales}, noise on, "
                f"float64 knee; windows of {base.window_steps} samples, feedback Lipschitz bound "
                f"{base.lipschitz_rad_per_rad} rad/rad, command-rate weight {base.rate_weight_s2:g} s^2; stop: < "
                f"{base.min_improvement:.0%} for {base.patience} epochs (cap {base.max_seconds:g} s); threads "
                f"{args.threads}; batch {knees} knees (steps/s: samples of the batch)")
    print(settings, flush=True)
    table = Table(COLUMNS)
    _, imitation, _ = train_reference_bundle(args.spring, args.out / "reference-ilc",
                                           capped_reference_settings(CAPS_S["reference"]))
    imitation_s = imitation.label_s + imitation.training.summary()["wall_s"]
    print(f"the reference network: ILC labels {imitation.label_s:.1f} s + network "
          f"{imitation.training.summary()['wall_s']:.1f} s = "
          f"{imitation_s:.0f} s -> {args.out / 'reference-ilc'}", flush=True)
    table.add("the reference network: ILC labels + network", "", "", "", "", f"{imitation_s:.0f}", "", "", "", "", "")
    print(" | ".join(COLUMNS))
    fine_tuning = replace(FINE_TUNING, threads=args.threads, max_seconds=CAPS_S["closedloop"])
    _, tuned, _ = train_closedloop_bundle(args.spring, args.out / "closedloop", fine_tuning,
                                          imitation=imitation)
    table.add(*_row("the closed-loop policy fine-tuning the reference network (default)", tuned, k, args.calls))
    _print(table.rows[-1])
    scratch = train_closed_loop(spring, base)
    export_closedloop_bundle(scratch, args.spring, args.out / "closedloop-scratch", {"init": "scratch"},
                             name="closedloop-scratch")
    table.add(*_row("the closed-loop policy from scratch", scratch, k, args.calls))
    _print(table.rows[-1])
    paths = _paths_us(args.out / "closedloop", args.calls)
    print("default bundle, one call of the flat forward (median): " + ", ".join(f"{p} {us:.1f} us" for p, us in
                                                                              paths.items())
          + f" (budget {STEP_BUDGET_US:.0f} us: {'within' if max(paths.values()) <= STEP_BUDGET_US else 'OVER'})")
    print(f"default `seadesign train` (the reference network, then fine-tuned): {imitation_s + tuned.wall_s:.0f} s "
          f"to a "
          f"converged "
          f"closed-loop corrector; from scratch {scratch.wall_s:.0f} s. Bundles in {args.out}. Other processes share "
          "this CPU.")
    if args.docs:
        write_fragment("closedloop_training", table, settings + f"; spring {args.spring}",
                       "Default bundle, one call of the flat forward (median): " + ", ".join(
                           f"{p} {us:.1f} us" for p, us in paths.items()) + ".")


if __name__ == "__main__":
    main()
