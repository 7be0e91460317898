"""Stage-by-stage timing of one candidate at the study's mesh size, and CalculiX on the same mesh.

Usage: python benchmarks/fea.py [--study wolfgang_knee] [--beams 8] [--thickness-mm 6]
       [--coarsening C] [--elements-across-beam N] [--backend gmsh|pytetwild] [--no-ccx]
       [--no-path] [--max-rotation-rad 0.4] [--contact]
Prints machine, settings, per-stage seconds and the ratio (our assembly + factorization + solve)
/ (ccx wall time, which includes its own input reading, assembly and solve). Then the
large-deflection path on the sweep's path mesh (the same sizing with SolverSettings.path_layers layers
through the thickness; fea.rotation_path, to the stall torque or where it stops, no strain stop):
its time split into assembly / factorization / solve / stop checks (the solver's methods timed from
here, the library unchanged), Newton iterations per increment, one assembly of the residual and the
tangent at the path's last state against scikit-fem's assembly of the same law (tests/helpers_skfem.py) and
under the calibration's Yeoh and Mooney-Rivlin trial laws,
and CalculiX NLGEOM on the same mesh and rotations with the time ratio and the torque agreement. --coarsening C makes every mesh size C
times coarser, as the sweep's error-estimate mesh (C = 4: a few minutes in all).
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
import time
from collections import defaultdict
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

import numpy as np

from seadesign.fea import rotation_path as rp
from seadesign.fea.assembly import UpperBlocks
from seadesign.fea.ccx_contact import pair_around
from seadesign.fea.contact import FrictionlessContact
from seadesign.fea.facing import FacingSurfaces
from seadesign.fea.ccx import (PathIncrements, path_nodes, run_ccx, run_ccx_path, write_load_case_decks,
                               write_path_inp)
from seadesign.fea.finite_strain import Solid
from seadesign.fea.loadcases import analyse
from seadesign.fea.pardiso import Pardiso
from seadesign.mesh import mesh_part
from seadesign.design.study import load_study
from seadesign.sweep.stages import SolverSettings
from seadesign.fea.elements import element_mesh
from seadesign.fea.linsolve import full_from_upper

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from helpers_skfem import neo_hooke_forms, skfem_permutation  # noqa: E402  the tests' independent law
from record import machine  # noqa: E402

# the path's time split: the methods timed in each part (a method called inside another is not nested here)
PATH_PARTS = {
    "assembly (forces, tangent, energy)": [(Solid, "forces"), (Solid, "tangent"), (Solid, "tangent_product"),
                                           (Solid, "energy"), (UpperBlocks, "matrix")],
    "factorization, ordering a new pattern": [(Pardiso, "__init__")],
    "factorization on the pattern ordered": [(Pardiso, "refactor")],
    "solve": [(Pardiso, "solve")],
    "stop checks (peak strain, contact gap)": [(Solid, "element_strain_stress"), (FacingSurfaces, "min_gap_mm")],
    "contact search": [(FrictionlessContact, "search")],
    "contact terms (forces, tangent blocks, energy)": [(FrictionlessContact, "forces"),
                                                       (FrictionlessContact, "tangent_blocks"),
                                                       (FrictionlessContact, "energy")],
}


@contextmanager
def timed(parts: dict) -> Iterator[dict]:
    """Wrap the listed methods to add their seconds and calls to {part: [s, calls]}; restored on exit."""
    totals: dict = defaultdict(lambda: [0.0, 0])
    saved = []
    for part, methods in parts.items():
        for owner, name in methods:
            original = getattr(owner, name)
            saved.append((owner, name, original))

            def wrapper(*a, _f=original, _part=part, **k):
                t = time.perf_counter()
                try:
                    return _f(*a, **k)
                finally:
                    totals[_part][0] += time.perf_counter() - t
                    totals[_part][1] += 1

            setattr(owner, name, wrapper)
    try:
        yield totals
    finally:
        for owner, name, original in saved:
            setattr(owner, name, original)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--study", default="wolfgang_knee")
    ap.add_argument("--beams", type=int, default=8)
    ap.add_argument("--thickness-mm", type=float, default=6.0)
    ap.add_argument("--coarsening", type=float, default=1.0, help="every mesh size this many times coarser")
    ap.add_argument("--elements-across-beam", type=float)
    ap.add_argument("--backend", choices=["gmsh", "pytetwild"], default="gmsh")
    ap.add_argument("--no-ccx", action="store_true")
    ap.add_argument("--no-path", action="store_true", help="skip the large-deflection path")
    ap.add_argument("--max-rotation-rad", type=float, default=0.4, help="where the path stops at the latest")
    ap.add_argument("--contact", action="store_true", help="the path through frictionless self-contact (the sweep's "
                    "setting), and CalculiX with a face-to-face contact pair where ours touches at the end")
    args = ap.parse_args()
    st = load_study(args.study)
    sizing = st.mesh.scaled(1.0 / args.coarsening)
    across = args.elements_across_beam or sizing.elements_across_beam
    per_circle = sizing.elements_per_circle if args.backend == "gmsh" else 0.0
    m, lc = st.material, st.load_cases

    stages: dict[str, float] = {}
    t = time.perf_counter()
    checked, part = st.check(st.candidate(beam_count=args.beams, beam_thickness_mm=args.thickness_mm))
    stages["CAD + validity"] = time.perf_counter() - t
    if not checked.valid:
        raise SystemExit(f"candidate is invalid: {checked.reasons}")
    with tempfile.TemporaryDirectory() as cache:  # fresh: no cached mesh
        def mesh_with(layers: int):
            return mesh_part(part.solid, part.interfaces, across, args.thickness_mm, cache_dir=cache,
                             backend=args.backend, elements_per_circle=per_circle,
                             layers=layers if args.backend == "gmsh" else 0)

        t = time.perf_counter()
        mesh = mesh_with(sizing.mesh_part_options()["layers"])
        t_mesh = time.perf_counter() - t
        path_mesh = None if args.no_path else mesh_with(SolverSettings().path_layers)
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

    print(f"machine: {machine()}")
    print(f"candidate: {args.beams} beams / {args.thickness_mm:g} mm ({st.name}), material {m.name}")
    print(f"mesh: {args.backend}, coarsening {args.coarsening:g}: {across:g} elements across the beam -> {mesh.info['target_edge_mm']:.3g} mm, "
          f"{per_circle:g} per turn on curved surfaces; "
          f"{mesh.quality.n_tets} tets, {mesh.quality.n_nodes} vertices, {int(r['dofs'])} P2 dofs, "
          f"min dihedral {mesh.quality.min_dihedral_deg:.1f} deg, max aspect {mesh.quality.max_aspect_ratio:.2f}")
    print(f"{'stage':<44}{'s':>9}")
    for name, s in stages.items():
        print(f"{name:<44}{s:>9.2f}")
    total = sum(stages.values())
    print(f"{'full candidate (both load cases, all outputs)':<44}{total:>9.2f}")
    print(f"k = {r['k_Nm_per_rad']:.5g} Nm/rad, equilibrium error {r['equilibrium_rel_error']:.1e}")
    use_ccx = not args.no_ccx and shutil.which("ccx") is not None
    if not use_ccx:
        print("CalculiX: skipped" + ("" if args.no_ccx else " (ccx not on PATH)"))
    else:
        linear_ccx(a, m, lc, r)
    if not args.no_path:
        path_benchmark(path_mesh, m, lc, args.max_rotation_rad, use_ccx, args.contact)


def linear_ccx(a, m, lc, r: dict) -> None:
    """CalculiX on the linear stall case: time, k and displacement agreement."""
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


def path_benchmark(mesh, m, lc, max_rotation_rad: float, use_ccx: bool, contact: bool) -> None:
    """The large-deflection path on the sweep's path mesh (this sizing, SolverSettings.path_layers layers through
    the thickness) with its time split, and CalculiX NLGEOM at the path's rotations (through contact: with a
    face-to-face contact pair, ten times our penalty, on the faces within 1.5 mm of where ours touches at the end)."""
    law = m.law
    print(f"path mesh: {len(mesh.tets)} tets, {SolverSettings().path_layers} layer(s) through the thickness")
    settings = rp.PathSettings(max_rotation_rad=max_rotation_rad)
    settings = rp.through_contact(settings) if contact else settings
    with timed(PATH_PARTS) as parts:
        path = rp.rotation_path(mesh, law, lc.stall_torque_Nm, settings)
    points = path.points[1:]
    its = np.array([p.iterations for p in points])
    factorizations = parts["factorization, ordering a new pattern"][1] + parts["factorization on the pattern ordered"][1]
    print(f"large-deflection path (neo-Hooke C10 {law.c10_Pa / 1e6:.3g} MPa, D1 {law.d1_per_Pa * 1e6:.3g} 1/MPa; "
          f"formulation full; to {lc.stall_torque_Nm:g} Nm or {max_rotation_rad:g} rad): stopped by {path.stop_reason} "
          f"at {path.stop_rotation_rad:.4f} rad, {path.stop_torque_Nm:.4g} Nm"
          + "".join(f"; {e.kind} at {e.rotation_rad:.4f} rad, {e.torque_Nm:.4g} Nm" for e in path.events))
    print(f"{len(points)} increments accepted, {path.cut_backs} cut back; Newton iterations per accepted increment "
          f"{its.mean():.2f} (max {its.max()}); {factorizations} tangent factorizations and "
          f"{parts['solve'][1]} solves in all (cut-back attempts included); MKL threads "
          f"{os.environ.get('MKL_NUM_THREADS') or os.environ.get('OMP_NUM_THREADS') or os.cpu_count()}")
    print(f"{'path part':<44}{'s':>9}{'calls':>8}{'ms / call':>12}")
    for name in PATH_PARTS:
        s, calls = parts.get(name, (0.0, 0))
        print(f"{name:<44}{s:>9.2f}{calls:>8}{1e3 * s / max(calls, 1):>12.1f}")
    other = path.time_s - sum(s for s, _ in parts.values())
    print(f"{'other (set-up, predictor, bookkeeping)':<44}{other:>9.2f}")
    print(f"{'path total':<44}{path.time_s:>9.2f}")
    assembly_vs_skfem(mesh, law, path.displacement_m)
    assembly_by_law(mesh, law, path.displacement_m)
    if not use_ccx:
        return
    theta = [p.rotation_rad for p in points]
    emesh, hub, ring = path_nodes(mesh)
    deck = None
    if contact and path.events:
        touch = rp.path_problem(mesh, law, settings).system.contact
        deck = pair_around(touch, path.displacement_m, 1.5, 10 * touch.penalty_Pa_per_m)
    with tempfile.TemporaryDirectory() as d:
        inp = write_path_inp(Path(d) / "path.inp", emesh, hub, ring, law, theta,
                             PathIncrements(max_rad=0.02) if deck else PathIncrements(), deck)
        cc = run_ccx_path(inp, emesh.nodes_m, theta)
    n = len(cc.torque_Nm)
    diff = np.abs(cc.torque_Nm / np.array([p.torque_Nm for p in points[:n]]) - 1)
    print(f"CalculiX NLGEOM{' with a contact pair' if deck else ''} {os.cpu_count()} threads (SPOOLES), same mesh, the path's {len(theta)} rotations: "
          f"{cc.wall_s:.2f} s wall, {cc.increments} increments, {cc.iterations} iterations "
          f"({cc.iterations / cc.increments:.2f} per increment, {1e3 * cc.wall_s / cc.iterations:.0f} ms each)"
          + (f"; did not converge: {cc.failure}" if cc.failure else ""))
    print(f"torque: max |T_ccx / T_ours - 1| = {diff.max():.1e} over {n} rotations to {theta[n - 1]:.4f} rad "
          f"(at the last: {diff[-1]:.1e})")
    touch = next((e.rotation_rad for e in path.events if e.kind == "contact"), None)
    if touch is not None:
        before = np.array(theta[:n]) < touch
        print("; ".join(f"{name}: {len(part)} rotations, max {part.max():.1e}" for name, part in
                        (("before contact", diff[before]), ("through contact", diff[~before])) if len(part)))
    print(f"ours (path total) / CalculiX = {path.time_s:.2f} / {cc.wall_s:.2f} = {path.time_s / cc.wall_s:.2f}")


def assembly_vs_skfem(mesh, law, u: np.ndarray) -> None:
    """Residual and tangent at u (the whole mesh, no constraints): ours against scikit-fem's assembly of the
    same neo-Hookean law, timed after one warm-up call each, with their largest difference."""
    from skfem import asm

    solid = Solid.of(element_mesh(mesh.points_mm * 1e-3, mesh.tets, 2), law)
    basis, perm = skfem_permutation(mesh.points_mm * 1e-3, mesh.tets, solid.mesh, intorder=2)
    residual, stiffness = neo_hooke_forms(law.c10_Pa, law.d1_per_Pa)
    prev = basis.interpolate(u.ravel()[perm])
    times = {}
    for name, fn in [("ours", lambda: (solid.forces(u), solid.tangent(u))),
                     ("scikit-fem", lambda: (asm(residual, basis, prev=prev), asm(stiffness, basis, prev=prev)))]:
        fn()
        t = time.perf_counter()
        out = fn()
        times[name] = time.perf_counter() - t
        if name == "ours":
            f, k = out[0].ravel()[perm], full_from_upper(out[1].matrix())[perm][:, perm]
        else:
            df, dk = np.abs(out[0] - f).max() / np.abs(out[0]).max(), abs(out[1] - k).max() / abs(out[1]).max()
    print(f"residual + tangent assembly at the last state: ours {times['ours']:.2f} s, scikit-fem "
          f"{times['scikit-fem']:.2f} s (ratio {times['ours'] / times['scikit-fem']:.3f}); largest difference "
          f"{df:.1e} (residual), {dk:.1e} (tangent), relative to the largest entry")



def assembly_by_law(mesh, law, u: np.ndarray, rounds: int = 5) -> None:
    """Residual and tangent at u under each law family at the material's mu (the calibration's trial laws: Yeoh
    through the I1-only kernel, Mooney-Rivlin through `fea.kernels.mooney_rivlin_pair_blocks`), after one warm-up
    call each: the least of `rounds` timings, the laws taking turns, against the material's own law in the same
    process."""
    from seadesign.calibration.law_family import trial_law

    laws = {"material's": law, "yeoh c20_ratio 0.05": trial_law(law, "yeoh", 0.05),
            "mooney_rivlin c01_share 0.5": trial_law(law, "mooney_rivlin", 0.5)}
    emesh = element_mesh(mesh.points_mm * 1e-3, mesh.tets, 2)
    solids = {name: Solid.of(emesh, each) for name, each in laws.items()}
    spent: dict[str, list[float]] = {name: [] for name in laws}
    for _ in range(rounds + 1):
        for name, solid in solids.items():
            t = time.perf_counter()
            solid.forces(u), solid.tangent(u)
            spent[name].append(time.perf_counter() - t)
    times = {name: min(s[1:]) for name, s in spent.items()}  # the first round warms up
    ref = times["material's"]
    print(f"residual + tangent assembly by law at the last state (least of {rounds}): " + ", ".join(
        f"{name} {t:.2f} s ({t / ref:.2f}x)" for name, t in times.items()))


if __name__ == "__main__":
    main()
