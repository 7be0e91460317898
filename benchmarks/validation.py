"""The validation tables the tests hold, measured again and written into the documentation: Rivlin's circular
shear, CalculiX NLGEOM against the path, the calibration loop's goal, and the loop on the real recordings.
Each table's test asserts its numbers within a tolerance; this script writes the numbers themselves.

Usage: python benchmarks/validation.py TABLE [TABLE ...] [--draws 3] [--docs]
TABLE: circular_shear (about 1 min), ccx_path (CalculiX `ccx` on PATH; about 7 min, `--default-mesh` about 10 min
more), loop_goal (3 draws:
about 15 min), loop_real (needs ../shared/data/deepsea; about 10 min). `--docs` writes
docs/validation/_fragments/TABLE.md.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from record import ROOT, Table, machine, write_fragment

sys.path.insert(0, str(ROOT / "tests"))  # the independent references: analytic meshes, generators


def circular_shear(args) -> tuple[Table, str]:
    from helpers_annulus import A_MM, B_MM, H_MM, circular_shear, radial_drift

    table = Table(["mesh (radial x around)", "rotation at Rivlin's 1 rad torque", "largest radius change of a vertex / "
                   "arc at 1 rad", "time (s)"])
    for n_r, n_theta in ((4, 48), (10, 120)):
        t0 = time.perf_counter()
        path, t1, _ = circular_shear(n_r, n_theta, 0.4999, "mean_dilatation")
        table.add(f"{n_r} x {n_theta}", f"{path.rotation_at(t1):.4f} rad", f"{radial_drift(path).max():.2%}",
                  f"{time.perf_counter() - t0:.0f}")
        print(table.rows[-1], flush=True)
    return table, (f"Neo-Hookean annulus {A_MM:g} / {B_MM:g} mm, {H_MM:g} mm high, nu 0.4999, faces held axially "
                   "(plane strain), mean-dilatation P2 tetrahedra; held by tests/test_fea_rotation_path.py")


def ccx_path(args) -> tuple[Table, str]:
    from helpers_annulus import annulus_mesh

    from seadesign.design.materials import Hyperelastic
    from seadesign.design.study import load_study
    from seadesign.fea.ccx import path_nodes, run_ccx_path, write_path_inp
    from seadesign.fea.rotation_path import PathSettings, rotation_path
    from seadesign.run.cache import Cache
    from seadesign.sweep.stages import tetrahedralize

    study = load_study()
    table = Table(["part", "tetrahedra", "rotations compared", "largest |T_ccx / T - 1|", "time ours / CalculiX (s)"])
    cases = [("annulus 5 / 12 / 3 mm", lambda: annulus_mesh(5.0, 12.0, 3.0, n_r=3, n_theta=16, n_z=2),
              Hyperelastic.from_linear(12e6, 0.48), 100.0, PathSettings(max_rotation_rad=0.5))]
    for beams, thickness_mm, step in ((3, 8.0, 0.1), (6, 6.0, 0.004)):
        def mesh(beams=beams, thickness_mm=thickness_mm):
            checked, part = study.check(study.candidate(beam_count=beams, beam_thickness_mm=thickness_mm))
            return tetrahedralize(study, checked, part, Cache(), coarsening=4.0)
        cases.append((f"{beams} beams x {thickness_mm:g} mm, mesh 4x coarser", mesh, study.material.law,
                      study.load_cases.stall_torque_Nm, PathSettings(max_rotation_rad=0.4, max_step_rad=step)))
    if args.default_mesh:  # the smallest of the default study's result meshes, to 0.1 rad
        def default_mesh():
            checked, part = study.check(study.candidate(beam_count=3, beam_thickness_mm=6.0))
            return tetrahedralize(study, checked, part, Cache())
        cases.append(("3 beams x 6 mm, the study's default mesh", default_mesh, study.material.law,
                      study.load_cases.stall_torque_Nm, PathSettings(max_rotation_rad=0.1)))
    work = Path(args.work)
    for name, make_mesh, law, target, settings in cases:
        mesh = make_mesh()
        t0 = time.perf_counter()
        path = rotation_path(mesh, law, target, settings)
        ours = time.perf_counter() - t0
        points = path.points[1:]
        theta = [p.rotation_rad for p in points]
        emesh, hub, ring = path_nodes(mesh)
        t0 = time.perf_counter()
        cc = run_ccx_path(write_path_inp(work / "path.inp", emesh, hub, ring, law, theta), emesh.nodes_m, theta)
        ccx_s = time.perf_counter() - t0
        n = len(cc.rotation_rad)
        worst = np.abs(cc.torque_Nm / np.array([p.torque_Nm for p in points[:n]]) - 1.0).max()
        reached = f"{n} of {len(theta)}, to {theta[n - 1]:.3g} rad ({path.stop_reason})"
        table.add(name, f"{len(mesh.tets):,}", reached + ("" if cc.failure is None else f"; CalculiX: {cc.failure}"),
                  f"{worst:.1e}", f"{ours:.0f} / {ccx_s:.0f}")
        print(table.rows[-1], flush=True)
    return table, ("C3D10, *HYPERELASTIC NEO HOOKE, NLGEOM, the same mesh, hub nodes driven to x' = R(theta) x and ring "
                   "nodes held, at the path's own rotations (formulation \"full\", CalculiX's); held by "
                   "tests/test_fea_ccx_path.py")


def loop_goal(args) -> tuple[Table, str]:
    from helpers_goal import GOAL, goal_recording
    from conftest import thesis_spring

    from seadesign.calibration import explain
    from seadesign.calibration.sea import robot_declared, robot_loop_data

    spring = thesis_spring()
    table = Table(["effect (range)", "plain model: named", "declared chain: named; unsupported",
                   "worst parameter error (test's tolerance)"])
    for case, (key, declared_name, param, bounds, _, tol, _) in GOAL.items():
        plain, declared, errors = [], [], []
        for draw in range(args.draws):
            df, value = goal_recording(case, draw)
            data = robot_loop_data(df, spring)
            ex = explain(data, [])
            plain.append(", ".join(ex.found) or "nothing")
            if key:
                errors.append(abs(ex.final.parameters()[key][param]["value"] / value - 1.0))
            ex = explain(data, robot_declared(spring))
            checks = {c.name: c for c in ex.declared}
            named = ", ".join(ex.found) or "nothing"
            if declared_name:
                named += f', "declared {checks[declared_name].declared[param]:.4g}, data says Y"'
                errors.append(abs(checks[declared_name].fitted[param]["value"] / value - 1.0))
            declared.append(f"{named}; {', '.join(ex.unsupported) or '-'}")
        span = "" if bounds is None else f" {bounds[0]:g}-{bounds[1]:g} ({param})"

        def tally(items):
            return "; ".join(f"{v} ({items.count(v)}/{len(items)})" for v in dict.fromkeys(items))

        table.add(f"{case}{span}", tally(plain), tally(declared),
                  f"{max(errors):.2%} ({tol:.1%})" if errors else "-")
        print(table.rows[-1], flush=True)
    return table, (f"{args.draws} draws per case of tests/helpers_goal.py (robot format, hanging knee stepping in "
                   "place, 100 Hz); the thesis's measured spring; declared chain: backlash and gear friction; held "
                   "by tests/test_calibration_goal.py")


def loop_real(args) -> tuple[Table, str]:
    from conftest import SHARED, thesis_spring

    from seadesign.data import KNEE_NAMES, clean, is_hanging, read_recording
    from seadesign.calibration import explain
    from seadesign.calibration.sea import robot_declared, robot_loop_data

    spring = thesis_spring()
    table = Table(["file, knee", "named (in order)", "declared, unsupported", "held-out RMSE before -> after (rad)"])
    for name in ("free_dtest_part1", "ground_dtest_part1", "d1free"):
        path = SHARED / "data" / "deepsea" / f"{name}.csv"
        if not path.exists():
            raise SystemExit(f"{path} is not present (../shared is outside the repository)")
        raw = read_recording(path)
        cleaned = clean(raw, keep_lifted=is_hanging(raw), normalise=False, euler=False).table
        for knee in ("l", "r"):
            ex = explain(robot_loop_data(cleaned, spring, knee), robot_declared(spring))
            table.add(f"{name}, {KNEE_NAMES[knee]}", ", ".join(ex.found), ", ".join(ex.unsupported) or "-",
                      f"{ex.plain.errors['held_out']['rmse']:.4g} -> {ex.final.errors['held_out']['rmse']:.4g}")
            print(table.rows[-1], flush=True)
    return table, ("`seadesign explain FILE --spring studies/thesis_measured_spring.json --knee l|r` on the recordings "
                   "in ../shared/data/deepsea/ (the data module's cleaning; declared chain: backlash and gear friction); "
                   "held by tests/test_calibration_real.py (to 1 %)")


TABLES = {"circular_shear": circular_shear, "ccx_path": ccx_path, "loop_goal": loop_goal, "loop_real": loop_real}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("tables", nargs="+", choices=list(TABLES))
    ap.add_argument("--draws", type=int, default=3, help="loop_goal: seeded draws per case")
    ap.add_argument("--work", default="exports/validation", help="ccx_path: CalculiX's working folder")
    ap.add_argument("--default-mesh", action="store_true",
                    help="ccx_path: also 3 beams x 6 mm on the study's default mesh (about 10 min more)")
    ap.add_argument("--docs", action="store_true", help="write docs/validation/_fragments/TABLE.md")
    args = ap.parse_args()
    Path(args.work).mkdir(parents=True, exist_ok=True)
    print(f"machine: {machine()}")
    for name in args.tables:
        print(f"\n{name}", flush=True)
        table, settings = TABLES[name](args)
        if args.docs:
            write_fragment(name, table, settings)


if __name__ == "__main__":
    main()
