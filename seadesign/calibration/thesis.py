"""The thesis case as a worked example: FEA material (generic TPU, E = 0.147 GPa) vs a bench test.

The thesis's FEA of the chosen 9-beam 8 mm part gave 0.3532 mm at r = 14 mm under 11.7 Nm, about
464 Nm/rad (Stelter 2022, sec. 5.1, fig. 5.4 and eq. 5.3); the bench measured k = 9.106 Nm/rad with a small
dead-band around zero (sec. 5.1, fig. 5.5).
Here the bench file is simulated from the measured k with a dead-band, and the loop explains it
with the FEA's k: it must find the stiffness scale (9.106 / 464 ~ 0.0196) and the dead-band.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from seadesign.constants import (THESIS_BEARING_RADIUS_M, THESIS_FEA_RESULTS, THESIS_K_MEASURED_NM_PER_RAD,
                                 XH540_STALL_TORQUE_NM)
from seadesign.data import write_bench
from seadesign.calibration.engine import Explanation, explain
from seadesign.calibration.report import write_report
from seadesign.calibration.sea import bench_loop_data, calibration
from seadesign.design.materials import load_material
from seadesign.twin import BenchProtocol, bench_effects, simulate_bench

# thesis FEA of the 9 x 8 mm part: its bearing displacement at r = 14 mm under the stall torque
K_FEA_NM_PER_RAD = XH540_STALL_TORQUE_NM / (THESIS_FEA_RESULTS[(9, 8.0)][1] * 1e-3 / THESIS_BEARING_RADIUS_M)
DEAD_BAND_RAD = 0.03


def linear(spring: dict[str, Any], k_Nm_per_rad: float) -> dict[str, Any]:
    """`spring` (a spring.json dict) as a linear spring of stiffness k: the thesis's FEA and bench were linear, so a
    torque curve of the given design is dropped."""
    return {key: value for key, value in spring.items() if key != "torque_curve"} | {"k_Nm_per_rad": k_Nm_per_rad}


def thesis_spring(spring: dict[str, Any]) -> dict[str, Any]:
    """`spring` (a spring.json dict) with the thesis FEA's k and material, linear."""
    material = load_material("generic_tpu")
    return {**linear(spring, K_FEA_NM_PER_RAD), "k_source": "fea", "material": material.to_handoff()}


def worked_example(spring: dict[str, Any], out_dir: Path, seed: int = 0) -> tuple[Explanation, dict[str, Any]]:
    """Simulate the bench file (measured k, dead-band), explain it with the FEA spring, write the report.

    Returns the explanation and the calibration dict (also written as `thesis_calibration.json`).
    """
    out_dir = Path(out_dir)
    chain = bench_effects(THESIS_K_MEASURED_NM_PER_RAD).configure("dead_band", enabled=True, width_rad=DEAD_BAND_RAD)
    table, meta = simulate_bench(linear(spring, THESIS_K_MEASURED_NM_PER_RAD), BenchProtocol(), effects=chain, seed=seed)
    write_bench(table, out_dir / "thesis_bench.csv", meta)
    fea = thesis_spring(spring)
    ex = explain(bench_loop_data(table, fea))
    bench = out_dir / "thesis_bench.csv"
    # the printed part's fitted modulus, expressed as the law of the given spring's material
    cal = calibration(ex, fea, bench, material=load_material(spring["material"]["name"]))
    write_report(ex, out_dir, "thesis", "Thesis case: FEA spring (generic TPU) vs bench with measured k and a dead-band",
                 loop_plot=True, calibration=cal)
    return ex, cal
