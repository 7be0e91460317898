"""The material law fitted from a bench curve: what the law families cost against full paths, how well they
interpolate, and the wall time of `explain` on a 3-minute 100 Hz bench file (goal: under 3 minutes on 2 cores).

For the spring of a sweep's spring.json (default: the default study's): the families' trial paths (two per
family, in worker processes), each family's interpolation against a full path at the midpoints between its nodes
(the largest torque difference over the common range, Nm), then a bench file written from the full path of a
Mooney-Rivlin part (C01 share 0.5, half the modulus; 0.02 Nm noise, 12-bit angles) explained with the law traced.
`--cold` uses an empty stage cache (every path computed, the spring's own too), as on a machine that did not run
the sweep. `--sweep` starts from what the uncalibrated sweep left in the default cache (run it first): the
geometry, the meshes, the linear solves and the study's own paths are copied to an empty cache, so that the
trial-law paths are computed; after the fit it re-ranks the spring's study with the calibration explain wrote
(`sweep --calibration`, every calibrated path computed): fit plus re-ranked sweep, goal under 10 minutes on 2
cores. Then the same for a stiffness error alone (a bench file of the spring's own curve at half its torque),
whose calibration scales the law, so that the re-ranked sweep reads the uncalibrated paths scaled.

Prints one table with the machine and settings. Run:
python benchmarks/law_fit.py [--spring exports/wolfgang_knee/spring.json] [--cold] [--sweep] [--docs]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from record import ROOT, Table, add_docs_option, machine, write_fragment


def bench_file(path: Path, curve, scale: float, reach_rad: float) -> Path:
    """3 minutes at 100 Hz through `scale` x the curve: two slow sweeps, 12-bit angles, 0.02 Nm torque noise."""
    rng = np.random.default_rng(0)
    t = np.arange(0.0, 180.0, 0.01)
    d = reach_rad * np.sin(2 * np.pi * t / 20.0) * (0.6 + 0.4 * np.sin(2 * np.pi * t / 67.0))
    step = 2 * np.pi / 4096
    tau = scale * np.sign(d) * curve.torque(np.abs(d)) + rng.normal(0.0, 0.02, t.size)
    pd.DataFrame({"time_s": t, "torque_Nm": tau, "deflection_rad": np.round(d / step) * step}).to_csv(path, index=False)
    return path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spring", type=Path, default=ROOT / "exports" / "wolfgang_knee" / "spring.json")
    ap.add_argument("--cold", action="store_true", help="an empty stage cache: every path computed")
    ap.add_argument("--sweep", action="store_true", help="from the uncalibrated sweep's cache, then the re-ranked sweep")
    add_docs_option(ap, "law_fit")
    args = ap.parse_args()
    spring = json.loads(args.spring.read_text())
    if args.cold or args.sweep:
        from seadesign.design.study import load_study
        from seadesign.mesh import MESH_STAGE
        from seadesign.run.cache import Cache, default_cache
        from seadesign.sweep.path_stage import path_key
        from seadesign.sweep.stages import SolverSettings

        warm, cold = default_cache(), Cache(Path(tempfile.mkdtemp(prefix="law_fit_cache_")))
        os.environ["SEADESIGN_CACHE"] = str(cold.root)
        for stage in ("geometry", MESH_STAGE, "fea", "coarse_k") if args.sweep else ():
            if (warm.root / stage).is_dir():
                shutil.copytree(warm.root / stage, cold.root / stage)
        study = load_study(spring["study"])
        for candidate in study.candidates() if args.sweep else ():
            kept = warm.path("path", path_key(study, candidate, SolverSettings()))
            if kept.exists():
                cold.path("path", kept.stem).parent.mkdir(parents=True, exist_ok=True)
                shutil.copy(kept, cold.path("path", kept.stem))
    from seadesign.calibration.explain_file import explain_file
    from seadesign.calibration.law_family import FAMILIES, law_families, path_curve, spring_source, trial_law

    cache = ("the uncalibrated sweep's geometry, meshes, linear solves and paths (--sweep)" if args.sweep
             else "empty (--cold)" if args.cold else "as it is")
    print(f"machine: {machine()}; spring {args.spring} ({spring['study']}); cache {cache}")
    t0 = time.perf_counter()
    source = spring_source(spring)
    t_source = time.perf_counter() - t0
    t0 = time.perf_counter()
    families = law_families(source, tuple(FAMILIES))
    t_families = time.perf_counter() - t0
    table = Table(["what", "paths", "wall time (s)", "largest torque difference (Nm)", "notes"])
    table.add("the spring's own path (spring.json checked against it)", 1, f"{t_source:.1f}", "-",
              f"{source.candidate.name}, ends at {source.path.stop_rotation_rad:.4g} rad ({source.path.stop_reason})")
    table.add("both families' trial paths (2 workers)", sum(len(f.nodes) - 1 for f in families.values()),
              f"{t_families:.1f}", "-", "; ".join(f"{m} nodes {', '.join(f'{v:g}' for v in f.nodes)}, common end "
                                                  f"{f.end_rad:.4g} rad" for m, f in families.items()))
    truth = None
    for model, family in families.items():
        for a, b in zip(family.nodes, family.nodes[1:]):
            v = 0.5 * (a + b)
            t0 = time.perf_counter()
            full = path_curve(source.with_law(trial_law(family.base, model, v)))
            spent = time.perf_counter() - t0
            d = np.linspace(0.0, min(full.rotation_rad[-1], family.end_rad), 200)
            error = float(np.max(np.abs(full.torque(d) - family.torque(d, v))))
            table.add(f"{model} {family.parameter} = {v:g}: full path vs interpolated", 1, f"{spent:.1f}",
                      f"{error:.2g}", f"end torque {full.torque_Nm[-1]:.4g} Nm")
            print(table.rows[-1], flush=True)
            if model == "mooney_rivlin" and truth is None and a <= 0.5 <= b:
                truth = path_curve(source.with_law(trial_law(family.base, model, 0.5)))
    folder = Path(tempfile.mkdtemp(prefix="law_fit_"))
    bench = bench_file(folder / "bench.csv", truth, 0.5, 0.9 * min(truth.rotation_rad[-1], families["yeoh"].end_rad))
    t0 = time.perf_counter()
    found = explain_file(bench, args.spring, out_dir=folder / "out")
    spent = time.perf_counter() - t0
    law = found.calibration["law"]
    mu_true = 0.5 * source.candidate.material.law.shear_modulus_Pa
    table.add("explain, 3-minute 100 Hz bench file (Mooney-Rivlin, share 0.5, half the modulus)", 0, f"{spent:.1f}",
              "-", f"named {', '.join(found.explanation.found)}; mu {law['mu_Pa'] / mu_true - 1:+.2%} off; "
                   f"{law['fitted'][-1]}")
    fit = t_source + t_families + spent
    totals = f"fit (spring's path + families + explain) {fit:.0f} s (goal under 180 s)"
    if args.sweep:
        from seadesign.sweep.pipeline import apply_calibration, sweep_and_write

        calibrated, _ = apply_calibration(study, found.files["calibration"])
        t0 = time.perf_counter()
        swept = sweep_and_write(calibrated, folder / "sweep", baseline=study, quiet=True)
        sweep_s = time.perf_counter() - t0
        table.add("sweep --calibration with that file (the uncalibrated sweep cached)",
                  len(swept.run.computed), f"{sweep_s:.1f}", "-", (swept.comparison or "").splitlines()[0])
        totals += f"; fit + re-ranked sweep {fit + sweep_s:.0f} s (goal under 600 s)"
        # a stiffness error alone: the spring's own curve at half its torque; its calibration scales the law, so the
        # re-ranked sweep reads the uncalibrated paths scaled (the families above are the fit's trial paths again)
        own = path_curve(source.path)
        scale_file = bench_file(folder / "scale.csv", own, 0.5, 0.9 * own.rotation_rad[-1])
        t0 = time.perf_counter()
        scaled = explain_file(scale_file, args.spring, out_dir=folder / "scale_out")
        spent = time.perf_counter() - t0
        table.add("explain, 3-minute 100 Hz bench file (the spring's own curve, half the modulus)", 0, f"{spent:.1f}",
                  "-", f"named {', '.join(scaled.explanation.found)}; mu "
                       f"{scaled.calibration['law']['mu_Pa'] / mu_true - 1:+.2%} off; law {scaled.calibration['law']['model']}")
        calibrated, _ = apply_calibration(study, scaled.files["calibration"])
        t0 = time.perf_counter()
        swept = sweep_and_write(calibrated, folder / "scale_sweep", baseline=study, quiet=True)
        scale_sweep_s = time.perf_counter() - t0
        table.add("sweep --calibration with that file (paths read scaled)", len(swept.run.computed),
                  f"{scale_sweep_s:.1f}", "-", (swept.comparison or "").splitlines()[0])
        scale_fit = t_source + t_families + spent
        totals += (f"; a stiffness error alone: fit {scale_fit:.0f} s, fit + re-ranked sweep "
                   f"{scale_fit + scale_sweep_s:.0f} s")
    print(table.markdown())
    print(totals)
    if args.docs:
        write_fragment("law_fit", table, f"spring {args.spring.relative_to(ROOT) if args.spring.is_relative_to(ROOT) else args.spring}, "
                       f"cache {'the uncalibrated sweep only' if args.sweep else 'empty' if args.cold else 'warm'}; the explain "
                       f"row's families come from the cache the rows above filled; {totals}")


if __name__ == "__main__":
    main()
