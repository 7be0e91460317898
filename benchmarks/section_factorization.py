"""What a factorization of the path's tangent costs on the sweep's 3D path mesh, against a plane section of the
same part at the same in-plane sizing: the floor under a path's time (docs/validation/timing.md).

Usage: python benchmarks/section_factorization.py [--candidates 6x8,8x4] [--repeats 3] [--docs]
Per candidate: the 3D tangent at rest on the free nodes of the path mesh (P2 tetrahedra, `SolverSettings.path_layers`
layers through the thickness; hub and ring prescribed), and a plane-elasticity stiffness on the P2 triangles of the
same mesh's top face (scikit-fem, `section_path.Section`; the nodes over the 3D hub and ring held), each factored by PARDISO's LDL^T
with inertia as the path factors (`fea.pardiso.Pardiso(..., indefinite=True)`) on the current MKL threads: the
analysis with the first factorization, and a refactorization on the same pattern, the fastest of `--repeats`,
back to back in one process. The section is not a model of the part yet (no finite strain, no contact, no
thickness calibration): it measures what its linear algebra would cost.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from record import Table, add_docs_option, machine, write_fragment
from section_path import Section, path_meshes
from skfem.models.elasticity import lame_parameters, linear_elasticity

from seadesign.design.study import load_study
from seadesign.fea.pardiso import Pardiso


def timed(upper: sp.csr_matrix | sp.bsr_matrix, repeats: int) -> tuple[float, float]:
    """The fastest analysis + factorization and the fastest refactorization (s) of `upper` over `repeats`."""
    first, again = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        f = Pardiso(upper, indefinite=True)
        t1 = time.perf_counter()
        f.refactor(upper)
        again.append(time.perf_counter() - t1)
        first.append(t1 - t0)
        f.close()
    return min(first), min(again)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--candidates", default="6x8,8x4", help="beams x thickness (mm), comma-separated")
    ap.add_argument("--repeats", type=int, default=3)
    add_docs_option(ap, "section_factorization")
    args = ap.parse_args()
    study = load_study()
    table = Table(["design", "model", "dofs", "analysis + factorization (s)", "refactorization (s)",
                   "refactorization against the 3D path mesh's"])
    with tempfile.TemporaryDirectory() as d:
        for checked, mesh, p in path_meshes(study, args.candidates, Path(d)):
            k3 = p.solid.tangent(np.zeros_like(p.solid.mesh.nodes_m), p.system.pattern).matrix()
            nodes, m = p.solid.mesh.nodes_m, study.material
            section = Section(mesh.points_mm, mesh.boundary_faces, nodes[p.drive.hub, :2], nodes[p.drive.ring, :2],
                              m.law.shear_modulus_Pa)
            k2 = linear_elasticity(*lame_parameters(m.youngs_modulus_Pa, m.poisson_ratio)).assemble(section.basis)
            k2 = sp.triu(k2[section.free][:, section.free]).tocsr()
            solid, plane = timed(k3, args.repeats), timed(k2, args.repeats)
            label = checked.name
            table.add(label, f"3D path mesh ({len(mesh.tets)} P2 tetrahedra)", k3.shape[0], f"{solid[0]:.3f}",
                      f"{solid[1]:.3f}", "1")
            table.add(label, "plane section (P2 triangles of its top face)", k2.shape[0], f"{plane[0]:.3f}",
                      f"{plane[1]:.3f}", f"1/{solid[1] / plane[1]:.1f}")
    settings = (f"Study {study.name}; PARDISO LDL^T with inertia, fastest of {args.repeats}, back to back in one "
                "process; the section: linear plane elasticity, the nodes over the 3D mesh's hub and ring held")
    print(f"machine: {machine()}\n{settings}\n{table.markdown()}")
    if args.docs:
        write_fragment("section_factorization", table, settings)


if __name__ == "__main__":
    main()
