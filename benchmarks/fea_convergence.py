"""Mesh convergence of k with Richardson extrapolation, and the run-to-run spread of k across
fresh pytetwild meshings.

Usage: python benchmarks/fea_convergence.py [--study wolfgang_knee] [--candidates 3x4,8x6,6x8]
       [--refinements 0.667,1,1.5,2.25] [--backend gmsh] [--spread N]
Prints, per candidate, k and the peak stall von Mises stress at each refinement (a factor on
the study's elements across the beam, elements per turn on curved surfaces and layers: 1 is the
study's default mesh), whether the peak converges, the extrapolated k,
the observed order, each size's estimated discretization error, and the sweep's two-level
estimate at the default (default vs the 1.5x coarser mesh) next to it; with --spread N, N fresh
pytetwild meshes of the first candidate at the study's size and the spread (max - min) / mean of k.
`--docs` writes the k table into docs/validation/_fragments/mesh_convergence_linear.md.
"""

from __future__ import annotations

import argparse
import tempfile
import time

import numpy as np
from record import Table, add_docs_option, machine, write_fragment

from seadesign.fea.convergence import richardson
from seadesign.fea.loadcases import analyse
from seadesign.mesh import mesh_part
from seadesign.sweep.stages import COARSENING, CONVERGENCE_ORDER
from seadesign.design.study import load_study


def k_at(st, part, width, refinement, backend, cache_dir) -> tuple[float, float, int, float]:
    """k (Nm/rad), peak stall von Mises (MPa), tetrahedra and seconds at one refinement."""
    t = time.perf_counter()
    sizing = st.mesh.scaled(refinement).mesh_part_options()
    if backend == "pytetwild":
        sizing.update(elements_per_circle=0.0, layers=0)
    mesh = mesh_part(part.solid, part.interfaces, beam_width_mm=width, cache_dir=cache_dir,
                     **{**sizing, "backend": backend}, max_tets=1_500_000, timeout_s=600)
    m, lc = st.material, st.load_cases
    r = analyse(mesh, m.youngs_modulus_Pa, m.poisson_ratio, m.yield_strength_Pa, lc.stall_torque_Nm,
                lc.impact_torque_Nm, st.bearing_radius_mm).results
    return r.k_Nm_per_rad, r.stall.stresses.von_mises_max.MPa, len(mesh.tets), time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--study", default="wolfgang_knee")
    ap.add_argument("--candidates", default="3x4,8x6,6x8", help="beams x thickness_mm, comma separated")
    ap.add_argument("--refinements", default="0.667,1,1.5,2.25", help="factors on the study's mesh density")
    ap.add_argument("--backend", choices=["gmsh", "pytetwild"], default="gmsh")
    ap.add_argument("--spread", type=int, default=0, help="fresh pytetwild meshings for the spread of k")
    add_docs_option(ap, "mesh_convergence_linear")
    args = ap.parse_args()
    st = load_study(args.study)
    refinements = [float(s) for s in args.refinements.split(",")]
    print(f"machine: {machine()}")
    docs = Table(["design", "k at refinement " + " / ".join(f"{f:g}" for f in refinements) + " (Nm/rad)",
                  "extrapolated k (Nm/rad)", "observed order", "error at the default mesh",
                  "peak stall von Mises at each refinement (MPa)"])
    print(f"study {st.name}, material {st.material.name}, backend {args.backend}, study default "
          f"{st.mesh.elements_across_beam:g} elements across the beam, {st.mesh.elements_per_circle:g} per turn "
          f"on curved surfaces")
    parts = []
    for spec in args.candidates.split(","):
        n, w = spec.split("x")
        checked, part = st.check(st.candidate(beam_count=int(n), beam_thickness_mm=float(w)))
        if not checked.valid:
            print(f"{spec}: invalid ({'; '.join(checked.reasons)})")
            continue
        parts.append((int(n), float(w), part))
    with tempfile.TemporaryDirectory() as cache:
        for n, w, part in parts:
            hs, ks, peaks = [], [], []
            print(f"\n{n} beams / {w:g} mm")
            print(f"{'refine':>7}{'h mm':>8}{'tets':>9}{'k Nm/rad':>12}{'stall vM max MPa':>18}{'s':>8}")
            for f in refinements:
                k, vm, tets, s = k_at(st, part, w, f, args.backend, cache)
                hs.append(1.0 / f)  # relative element size
                ks.append(k)
                peaks.append(vm)
                print(f"{f:>7g}{w / (f * st.mesh.elements_across_beam):>8.3f}{tets:>9}{k:>12.5f}{vm:>18.4f}{s:>8.1f}",
                      flush=True)
            if len(ks) < 3:
                continue
            steps = np.diff(peaks)
            print("peak stall von Mises, change per refinement step: "
                  + ", ".join(f"{100 * d / p:+.2f} %" for d, p in zip(steps, peaks[:-1]))
                  + (" (one sign, shrinking: converging)" if np.all(np.abs(steps[1:]) < np.abs(steps[:-1]))
                     and len(set(np.sign(steps))) == 1 else " (not a converging sequence)"))
            r = richardson(hs, ks)
            print(f"Richardson (finest three): k0 = {r['extrapolated']:.5f} Nm/rad, observed order {r['order']:.2f}")
            for f, h, k in zip(refinements, hs, ks):
                print(f"  refinement {f:g}: error against k0 {100 * (k - r['extrapolated']) / r['extrapolated']:+.2f} %")
            default = (f"{(ks[refinements.index(1.0)] / r['extrapolated'] - 1):+.2%}" if 1.0 in refinements else "-")
            docs.add(f"{n} beams x {w:g} mm", " / ".join(f"{k:.3f}" for k in ks), f"{r['extrapolated']:.3f}",
                     f"{r['order']:.2f}", default, " / ".join(f"{v:.3g}" for v in peaks))
            coarse = round(1 / COARSENING, 3)
            if 1.0 in refinements and coarse in [round(f, 3) for f in refinements]:
                k1 = ks[refinements.index(1.0)]
                kc = ks[[round(f, 3) for f in refinements].index(coarse)]
                est = abs(kc - k1) / k1 / (COARSENING**CONVERGENCE_ORDER - 1.0)
                print(f"  sweep's two-level estimate at the default: {100 * est:.2f} % "
                      f"(order {CONVERGENCE_ORDER:g} assumed)")
        if args.spread and parts:
            n, w, part = parts[0]
            ks = []
            for i in range(args.spread):
                with tempfile.TemporaryDirectory() as fresh:
                    k, _, tets, s = k_at(st, part, w, 1.0, "pytetwild", fresh)
                ks.append(k)
                print(f"pytetwild fresh mesh {i + 1}: {tets} tets, k = {k:.5f} Nm/rad ({s:.0f} s)", flush=True)
            ks = np.array(ks)
            print(f"spread of k over {len(ks)} fresh pytetwild meshes ({n} beams / {w:g} mm): "
                  f"{100 * np.ptp(ks) / ks.mean():.2f} % (max - min) / mean")
    if args.docs and docs.rows:
        write_fragment("mesh_convergence_linear", docs, f"Study {st.name}, material {st.material.name}, mesher "
                       f"{args.backend}; refinement: a factor on the study's mesh density (1: the default mesh, "
                       f"{st.mesh.elements_across_beam:g} elements across the beam); Richardson extrapolation over "
                       "the finest three")


if __name__ == "__main__":
    main()
