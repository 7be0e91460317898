"""Mesh convergence of k with Richardson extrapolation, and the run-to-run spread of k across
fresh pytetwild meshings.

Usage: python benchmarks/fea_convergence.py [--study wolfgang_knee] [--candidates 3x4,8x6,6x8]
       [--sizes 1.5,2,3] [--backend gmsh] [--spread N]
Prints, per candidate, k at each elements-across-beam setting, the extrapolated k, the observed
order and each size's estimated discretization error; with --spread N, N fresh pytetwild meshes
of the first candidate at the study's size and the spread (max - min) / mean of k.
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time

import numpy as np

from seadesign.candidates import check_candidate, find_candidate
from seadesign.fea.convergence import richardson
from seadesign.fea.torsion import solve_unit_torsion
from seadesign.mesh import mesh_part
from seadesign.study import load_study


def k_at(st, part, width, across, backend, cache_dir) -> tuple[float, int, float]:
    t = time.perf_counter()
    mesh = mesh_part(part.solid, part.interfaces, across, width, cache_dir=cache_dir, backend=backend)
    sol = solve_unit_torsion(mesh, st.material.youngs_modulus_Pa, st.material.poisson_ratio)
    return 1.0 / float(sol.hub_motion[5]), len(mesh.tets), time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--study", default="wolfgang_knee")
    ap.add_argument("--candidates", default="3x4,8x6,6x8", help="beams x thickness_mm, comma separated")
    ap.add_argument("--sizes", default="1.5,2,3", help="elements across the beam")
    ap.add_argument("--backend", choices=["gmsh", "pytetwild"], default="gmsh")
    ap.add_argument("--spread", type=int, default=0, help="fresh pytetwild meshings for the spread of k")
    args = ap.parse_args()
    st = load_study(args.study)
    sizes = [float(s) for s in args.sizes.split(",")]
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}, python {platform.python_version()}")
    print(f"study {st.name}, material {st.material.name}, backend {args.backend}, study default "
          f"{st.mesh.elements_across_beam:g} elements across the beam")
    parts = []
    for spec in args.candidates.split(","):
        n, w = spec.split("x")
        checked = check_candidate(st, find_candidate(st, int(n), float(w)))
        if not checked.valid:
            print(f"{spec}: invalid ({'; '.join(checked.reasons)})")
            continue
        parts.append((int(n), float(w), checked.part))
    with tempfile.TemporaryDirectory() as cache:
        for n, w, part in parts:
            hs, ks = [], []
            print(f"\n{n} beams / {w:g} mm")
            print(f"{'across':>7}{'h mm':>8}{'tets':>9}{'k Nm/rad':>12}{'s':>8}")
            for across in sizes:
                k, tets, s = k_at(st, part, w, across, args.backend, cache)
                hs.append(w / across)
                ks.append(k)
                print(f"{across:>7g}{w / across:>8.3f}{tets:>9}{k:>12.5f}{s:>8.1f}", flush=True)
            r = richardson(hs, ks)
            print(f"Richardson: k0 = {r['extrapolated']:.5f} Nm/rad, observed order {r['order']:.2f}")
            for h in hs:
                print(f"  estimated error at h = {h:.3f} mm: {100 * r[f'rel_error_h={h:g}']:.2f} %")
        if args.spread and parts:
            n, w, part = parts[0]
            ks = []
            for i in range(args.spread):
                with tempfile.TemporaryDirectory() as fresh:
                    k, tets, s = k_at(st, part, w, st.mesh.elements_across_beam, "pytetwild", fresh)
                ks.append(k)
                print(f"pytetwild fresh mesh {i + 1}: {tets} tets, k = {k:.5f} Nm/rad ({s:.0f} s)", flush=True)
            ks = np.array(ks)
            print(f"spread of k over {len(ks)} fresh pytetwild meshes ({n} beams / {w:g} mm): "
                  f"{100 * np.ptp(ks) / ks.mean():.2f} % (max - min) / mean")


if __name__ == "__main__":
    main()
