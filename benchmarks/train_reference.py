"""The reference network benchmark: ILC labels in the knee simulator and the reference-window network trained on them.

Reports the label stage (ILC iterations per batch, simulated knee steps per second, wall time), the
training (samples/s, epochs, stop reason, wall time to the early stop: no better validation MSE on
held-out trials for `patience` epochs), and the online step of the trained corrector (window buffer +
NumPy network; and the network alone under ONNX Runtime), median over many calls.

    python benchmarks/train_reference.py --spring exports/wolfgang_knee/spring.json [--calls 5000] [--out DIR]

`--out DIR` keeps the trained bundle (e.g. for benchmarks/closed_loop_goal.py).
"""

from __future__ import annotations

import argparse
import tempfile
import time

import numpy as np
import torch

from seadesign.corrector.export import NumpyCorrector, export_bundle, numpy_arrays
from seadesign.corrector.imitation import ImitationSettings, train_imitation
from seadesign.corrector.reference import Preview
from seadesign.corrector.runtime import ReferenceFeedForward
from seadesign.corrector.workflow import train_reference_bundle
from seadesign.design.spring import load_spring
from seadesign.onnx_corrector import load_onnx
from record import machine


def _median_us(fn, calls: int) -> float:
    for _ in range(200):
        fn()
    times = np.empty(calls)
    for i in range(calls):
        t0 = time.perf_counter()
        fn()
        times[i] = time.perf_counter() - t0
    return float(np.median(times) * 1e6)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spring", required=True, help="spring.json (e.g. from `seadesign sweep`)")
    ap.add_argument("--calls", type=int, default=5000)
    ap.add_argument("--out", default=None, help="write the trained bundle here")
    args = ap.parse_args()
    spring = load_spring(args.spring)
    settings = ImitationSettings()
    print(f"machine: {machine()}; torch {torch.__version__}")
    print(f"spring: {args.spring} (k {spring['k_Nm_per_rad']:.4g} Nm/rad, curve: {'torque_curve' in spring}); "
          f"labels: {len(settings.trials())} trials x {settings.trial_s:g} s at {settings.rate_hz:g} Hz, settings "
          f"{', '.join(settings.conditions)}, k scales {settings.k_scales}; training threads {settings.train.threads}, "
          f"batch {settings.train.batch_size}, patience {settings.train.patience} epochs")
    if args.out:
        _, res, _ = train_reference_bundle(args.spring, args.out, settings)
    else:
        res = train_imitation(spring, settings)
    steps = sum(len(r.mean_abs_error_rad) * r.target_rad.shape[0] * r.target_rad.shape[1] for r in res.labels)
    print(f"{'batch':<22} {'iterations':>10} {'best':>5} {'error_first_rad':>16} {'error_best_rad':>15}")
    for r in res.labels:
        print(f"{('ground' if r.ground else 'hanging') + f' k {r.k_Nm_per_rad:.3g}':<22} {len(r.mean_abs_error_rad):>10} "
              f"{r.best_iteration:>5} {r.mean_abs_error_rad[0]:>16.4f} {r.mean_abs_error_rad[r.best_iteration]:>15.4f}")
    s = res.training.summary()
    print(f"labels: {res.label_s:.1f} s, {steps / res.label_s:.0f} simulated trial steps/s (both knees each)")
    print(f"training: {s['epochs_run']} epochs, best {s['best_epoch']}, stop {s['stopped']}, {s['wall_s']:.1f} s, "
          f"{s['samples_per_s']:.0f} samples/s, best validation MSE {s['best_val_mse_rad2']:.3g} rad^2")
    print(f"wall time to a converged corrector: {res.label_s + s['wall_s']:.0f} s")
    npc = NumpyCorrector(numpy_arrays(res.training.net))
    corrector = ReferenceFeedForward(npc, settings.window, spring["k_Nm_per_rad"], kp=0.1, ki=0.5)
    preview = Preview(np.linspace(1.0, 1.2, settings.window.preview), np.full(settings.window.preview + 1, 0.5))
    measured = {"hall_pos_rad": 1.0}
    step_us = _median_us(lambda: corrector.command("right", -1.0, measured, 0.01, preview), args.calls)
    x = np.zeros(len(settings.window.feature_names()), dtype=np.float32)
    with tempfile.TemporaryDirectory() as tmp:
        bundle = export_bundle(res.training.net, {"inputs": list(settings.window.feature_names())}, tmp)
        onnx = load_onnx(bundle)
        onnx_us = _median_us(lambda: onnx(x), args.calls)
    np_us = _median_us(lambda: npc(x), args.calls)
    print(f"latency (median, single call): online step {step_us:.1f} us (window buffer + NumPy network), "
          f"NumPy network {np_us:.1f} us, ONNX Runtime network {onnx_us:.1f} us. Other processes share this CPU.")


if __name__ == "__main__":
    main()
