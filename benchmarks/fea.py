"""Stage-by-stage timing of one candidate at the study's mesh size, and CalculiX on the same mesh.

Usage: python benchmarks/fea.py [--study wolfgang_knee] [--beams 8] [--thickness-mm 6]
       [--elements-across-beam N] [--backend gmsh|pytetwild] [--no-ccx]
Prints machine, settings, per-stage seconds and the ratio (our assembly + factorization + solve)
/ (ccx wall time, which includes its own input reading, assembly and solve).
"""

from __future__ import annotations

import argparse
import os
import platform
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from seadesign.fea.ccx import run_ccx, write_load_case_decks
from seadesign.fea.loadcases import analyse
from seadesign.mesh import mesh_part
from seadesign.design.study import load_study


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--study", default="wolfgang_knee")
    ap.add_argument("--beams", type=int, default=8)
    ap.add_argument("--thickness-mm", type=float, default=6.0)
    ap.add_argument("--elements-across-beam", type=float)
    ap.add_argument("--backend", choices=["gmsh", "pytetwild"], default="gmsh")
    ap.add_argument("--no-ccx", action="store_true")
    args = ap.parse_args()
    st = load_study(args.study)
    across = args.elements_across_beam or st.mesh.elements_across_beam
    per_circle = st.mesh.elements_per_circle if args.backend == "gmsh" else 0.0
    m, lc = st.material, st.load_cases

    stages: dict[str, float] = {}
    t = time.perf_counter()
    checked, part = st.check(st.candidate(beam_count=args.beams, beam_thickness_mm=args.thickness_mm))
    stages["CAD + validity"] = time.perf_counter() - t
    if not checked.valid:
        raise SystemExit(f"candidate is invalid: {checked.reasons}")
    with tempfile.TemporaryDirectory() as cache:  # fresh: no cached mesh
        t = time.perf_counter()
        mesh = mesh_part(part.solid, part.interfaces, across, args.thickness_mm,
                         cache_dir=cache, backend=args.backend, elements_per_circle=per_circle,
                         layers=st.mesh.mesh_part_options()["layers"] if args.backend == "gmsh" else 0)
        t_mesh = time.perf_counter() - t
    stages["tessellation / BREP export"] = mesh.info["geometry_s"]
    stages["tetrahedralization (child process)"] = mesh.info["tetrahedralize_s"]
    stages["boundaries + quality"] = t_mesh - mesh.info["geometry_s"] - mesh.info["tetrahedralize_s"]
    t = time.perf_counter()
    a = analyse(mesh, m.youngs_modulus_Pa, m.poisson_ratio, m.yield_strength_Pa, lc.stall_torque_Nm,
                lc.impact_torque_Nm, st.bearing_radius_mm)
    t_fea = time.perf_counter() - t
    r = a.results.columns()
    for key in ("setup", "assembly", "factorization", "solve", "stress"):
        stages[f"FEA {key}" + (" (L2 projection, invariants)" if key == "stress" else "")] = r[f"time_{key}_s"]
    stages["FEA other (load-case numbers)"] = t_fea - sum(r[f"time_{k}_s"] for k in ("setup", "assembly", "factorization", "solve", "stress"))

    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"load average {os.getloadavg()[0]:.1f}; python {platform.python_version()}")
    print(f"candidate: {args.beams} beams / {args.thickness_mm:g} mm ({st.name}), material {m.name}")
    print(f"mesh: {args.backend}, {across:g} elements across the beam -> {mesh.info['target_edge_mm']:.3g} mm, "
          f"{per_circle:g} per turn on curved surfaces; "
          f"{mesh.quality.n_tets} tets, {mesh.quality.n_nodes} vertices, {int(r['dofs'])} P2 dofs, "
          f"min dihedral {mesh.quality.min_dihedral_deg:.1f} deg, max aspect {mesh.quality.max_aspect_ratio:.2f}")
    print(f"{'stage':<44}{'s':>9}")
    for name, s in stages.items():
        print(f"{name:<44}{s:>9.2f}")
    total = sum(stages.values())
    print(f"{'full candidate (both load cases, all outputs)':<44}{total:>9.2f}")
    print(f"k = {r['k_Nm_per_rad']:.5g} Nm/rad, equilibrium error {r['equilibrium_rel_error']:.1e}")
    if args.no_ccx or shutil.which("ccx") is None:
        print("CalculiX: skipped" + ("" if args.no_ccx else " (ccx not on PATH)"))
        return
    with tempfile.TemporaryDirectory() as d:
        decks = write_load_case_decks(Path(d), a.unit, m.youngs_modulus_Pa, m.poisson_ratio,
                                      lc.stall_torque_Nm, lc.impact_torque_Nm)
        cc = run_ccx(decks["stall"], len(a.unit.emesh.nodes_m))
    ours = r["time_assembly_s"] + r["time_factorization_s"] + r["time_solve_s"]
    u = a.displacement_m("stall")
    print(f"CalculiX {os.cpu_count()} threads (SPOOLES), same mesh and couplings: {cc.wall_s:.2f} s wall; "
          f"k = {lc.stall_torque_Nm / cc.rotation_rad:.5g} Nm/rad "
          f"(rel. diff {abs(lc.stall_torque_Nm / cc.rotation_rad / r['k_Nm_per_rad'] - 1):.1e}), "
          f"max |du| / max |u| = {np.abs(cc.displacement_m - u).max() / np.abs(u).max():.1e}")
    print(f"ours (assembly + factorization + solve) / CalculiX = {ours:.2f} / {cc.wall_s:.2f} = {ours / cc.wall_s:.2f}")


if __name__ == "__main__":
    main()
