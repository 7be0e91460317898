"""Corrector training and inference benchmark.

Trains each model on the real recordings (../shared/data/deepsea, cleaned by the data module)
when present, else on synthetic linear-spring recordings, and reports training throughput
(samples/s), wall time to convergence (early stop), and the single-sample inference latency of
the exported model (TorchScript frozen: forward on a ready input vector and the online step();
the NumPy path; corrector.onnx under ONNX Runtime, 1 thread), median over many calls.

    python benchmarks/train.py [--models mlp,siamese,history,residual] [--calls 5000] [--threads 2]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np
import torch

from seadesign.corrector.dataset import DatasetSpec, build_dataset
from seadesign.corrector.export import export_bundle, input_list, load_numpy, load_torchscript
from seadesign.corrector.recordings import load_recordings
from seadesign.corrector.runtime import STEP_BUDGET_US
from seadesign.corrector.splits import time_block_split
from seadesign.corrector.synthetic import linear_spring_recording
from seadesign.corrector.train import TrainConfig, fit
from seadesign.onnx_corrector import load_onnx
from record import machine

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data" / "deepsea"
K = 9.106  # Nm/rad, the thesis's measured spring


def _latency_us(fn, x, calls: int) -> float:
    for _ in range(200):
        fn(x)
    times = np.empty(calls)
    for i in range(calls):
        t0 = time.perf_counter()
        fn(x)
        times[i] = time.perf_counter() - t0
    return float(np.median(times) * 1e6)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--models", default="mlp,siamese,history,residual")
    ap.add_argument("--calls", type=int, default=5000)
    ap.add_argument("--threads", type=int, default=min(2, os.cpu_count() or 1))
    ap.add_argument("--max-seconds", type=float, default=60.0)
    args = ap.parse_args()

    files = sorted(SHARED.glob("*.csv")) if SHARED.exists() else []
    recs = load_recordings(files) if files else [linear_spring_recording(K, 30.0, seed=s, name=f"syn{s}")
                                                 for s in range(3)]
    source = "real: " + ", ".join(f.name for f in files) if files else "synthetic (../shared absent)"
    print(f"machine: {machine()}; torch {torch.__version__}")
    print(f"data: {source}; task thesis, modalities velocity_effort, positive; split time_blocks; "
          f"training threads {args.threads}, device {'cuda' if torch.cuda.is_available() else 'cpu'}")
    header = (f"{'model':<10} {'samples':>8} {'batch':>6} {'epochs':>7} {'best':>5} {'stop':>10} {'wall_s':>7} "
              f"{'samples_per_s':>14} {'val_mse_rad2':>13} {'ts_latency_us':>14} {'step_latency_us':>16} "
              f"{'np_latency_us':>14} {'onnx_latency_us':>16}")
    print(header)
    over = []
    for model in args.models.split(","):
        spec = DatasetSpec("thesis", "velocity_effort", 3 if model == "history" else 0, True)
        ds = build_dataset(recs, spec)
        cfg = TrainConfig(model=model, threads=args.threads, max_seconds=args.max_seconds)
        res = fit(ds, time_block_split(ds), K, cfg)
        with tempfile.TemporaryDirectory() as tmp:
            meta = {"inputs": input_list(ds.feature_names, model == "siamese"), "dataset": spec.to_dict()}
            bundle = export_bundle(res.net, meta, tmp)
            ts, npc = load_torchscript(bundle), load_numpy(bundle)
            x = np.concatenate([ds.X[0], ds.X_next[0]]) if model == "siamese" else ds.X[0]
            before = torch.get_num_threads()
            torch.set_num_threads(1)
            with torch.inference_mode():
                xt = torch.as_tensor(x[None, :], dtype=torch.float32)
                ts_us = _latency_us(ts, xt, args.calls)
                m = torch.zeros(len(ts.measured_names()))
                step_us = _latency_us(lambda v: ts.step(1, 0.5, v), m, args.calls)
            torch.set_num_threads(before)
            np_us = _latency_us(npc, x.astype(np.float32), args.calls)
            onnx_us = _latency_us(load_onnx(bundle), x.astype(np.float32), args.calls)
        lat = {"ts": ts_us, "step": step_us, "np": np_us, "onnx": onnx_us}
        over += [f"{model} {path} {us:.1f} us" for path, us in lat.items() if us > STEP_BUDGET_US]
        s = res.summary()
        print(f"{model:<10} {len(ds):>8} {cfg.batch_size:>6} {s['epochs_run']:>7} {s['best_epoch']:>5} "
              f"{s['stopped']:>10} {s['wall_s']:>7.1f} {s['samples_per_s']:>14.0f} {s['best_val_mse_rad2']:>13.3g} "
              f"{ts_us:>14.1f} {step_us:>16.1f} {np_us:>14.1f} {onnx_us:>16.1f}")
    print("latency: median of single-sample calls, 1 torch thread (step: the online TorchScript path with "
          "history and mirroring; onnx: ONNX Runtime, 1 intra-op thread, sequential); samples_per_s counts training samples "
          "seen per second of wall time (incl. validation each epoch). Other processes share this CPU.")
    print(f"budget {STEP_BUDGET_US:.0f} us per call (1 kHz loop): " + ("over: " + ", ".join(over) if over else "every path within"))


if __name__ == "__main__":
    main()
