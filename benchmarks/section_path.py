"""How far a plane section's large-deflection path lies from the 3D path of the same part, before contact: the
first question a section model must answer before it could stand in for the 3D path (docs/validation/timing.md).

Usage: python benchmarks/section_path.py [--candidates 8x4,6x8] [--docs]
Per candidate: the 3D path on the sweep's path mesh without contact forces (`fea.rotation_path`, to where the gap
closes), and at the same hub rotations the plane section made of the same mesh's top-face triangles (P2, scikit-fem
forms): finite strain in plane stress with the incompressible neo-Hookean law at the material's shear modulus mu,
W = mu / 2 (tr C + 1 / det C - 3) per unit volume (C: the in-plane right Cauchy-Green tensor; the thickness
stretch is 1 / det F), the nodes over the 3D hub turned rigidly and those over the ring held, full Newton from the
last two points' extrapolation. The section's thickness is matched to the 3D torque at the first point. Printed
as a check of the forms: the section's torque at 1e-4 rad against linear plane-stress elasticity on the same
triangles (E = 3 mu, nu = 1/2). The section is not a model of the part in the tool: this measures the error
such a model would carry.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import skfem
from record import Table, add_docs_option, machine, write_fragment
from scipy.spatial import cKDTree
from skfem.helpers import ddot, det, grad, inv, mul, transpose
from skfem.models.elasticity import linear_elasticity

from seadesign.design.candidate import Candidate
from seadesign.design.study import Study, load_study
from seadesign.fea.hub_rotation import HubRotation, moment_z
from seadesign.fea.pardiso import Pardiso
from seadesign.fea.rotation_path import PathProblem, PathSettings, path_problem, rotation_path
from seadesign.fea.torsion import MM
from seadesign.run.cache import Cache
from seadesign.mesh.tetmesh import TetMesh
from seadesign.sweep.stages import SolverSettings, tetrahedralize

ROTATION_CHECK_RAD = 1e-4  # the small rotation of the forms' check against linear plane stress
COMPARED_RAD = (0.1, 0.2)  # rotations (rad) where the table compares the torques


def _deformation(w):
    F = grad(w["u"]).copy()  # the field's own gradient is shared between calls
    F[0, 0] += 1.0
    F[1, 1] += 1.0
    return F


@skfem.LinearForm
def internal_forces(v, w):
    """The first Piola-Kirchhoff stress P = mu (F - F^-T / J^2) against the test gradient (per unit thickness)."""
    F = _deformation(w)
    return ddot(w["mu"] * (F - transpose(inv(F)) / det(F) ** 2), grad(v))


@skfem.BilinearForm
def tangent_stiffness(du, v, w):
    """dP : grad(du) = mu (du + 2 (F^-T : du) F^-T / J^2 + F^-T du^T F^-T / J^2) against the test gradient."""
    F = _deformation(w)
    fit, d = transpose(inv(F)), grad(du)
    j2 = det(F) ** 2
    return ddot(w["mu"] * (d + 2.0 * ddot(fit, d) * fit / j2 + mul(mul(fit, transpose(d)), fit) / j2), grad(v))


@skfem.Functional
def strain_energy(w):
    F = _deformation(w)
    return 0.5 * w["mu"] * (ddot(F, F) + 1.0 / det(F) ** 2 - 3.0)


class Section:
    """The plane section: P2 triangles of the 3D mesh's top face (m), the dofs over the 3D hub and ring prescribed."""

    def __init__(self, points_mm: np.ndarray, boundary_faces: np.ndarray, hub_xy_m: np.ndarray, ring_xy_m: np.ndarray,
                 mu_Pa: float) -> None:
        z = points_mm[:, 2]
        top = boundary_faces[np.all(np.isclose(z[boundary_faces], z.max()), axis=1)]
        used = np.unique(top)
        index = np.full(len(points_mm), -1)
        index[used] = np.arange(len(used))
        mesh = skfem.MeshTri(np.ascontiguousarray(points_mm[used, :2].T * MM), np.ascontiguousarray(index[top].T))
        self.basis = skfem.Basis(mesh, skfem.ElementVector(skfem.ElementTriP2()), intorder=4)
        self.mu = mu_Pa
        pairs = np.concatenate([self.basis.nodal_dofs.T, self.basis.facet_dofs.T])  # (locations, 2): x and y dofs
        self.xy = self.basis.doflocs[:, pairs[:, 0]].T

        def over(points_xy: np.ndarray) -> np.ndarray:
            distance, _ = cKDTree(points_xy).query(self.xy, distance_upper_bound=1e-9)
            return pairs[np.isfinite(distance)]

        self.hub, self.ring = over(hub_xy_m), over(ring_xy_m)
        self.free = np.setdiff1d(np.arange(self.basis.N), np.concatenate([self.hub.ravel(), self.ring.ravel()]))
        self.hub_xy = self.basis.doflocs[:, self.hub[:, 0]].T
        hub_nodes = np.column_stack([self.hub_xy, np.zeros(len(self.hub_xy))])
        self.drive = HubRotation(hub_nodes, np.arange(len(hub_nodes)), np.array([], dtype=int))  # the hub's motion

    def with_hub(self, u: np.ndarray, theta: float) -> np.ndarray:
        """u with the hub turned by theta (rad) and the ring held."""
        u = u.copy()
        u[self.hub] = self.drive.displacement(theta)[:, :2]
        u[self.ring.ravel()] = 0.0
        return u

    def forces(self, u: np.ndarray) -> np.ndarray:
        return internal_forces.assemble(self.basis, u=self.basis.interpolate(u), mu=self.mu)

    def torque(self, u: np.ndarray, f: np.ndarray) -> float:
        """The hub's reaction torque per unit thickness (Nm/m)."""
        return moment_z(self.hub_xy + u[self.hub], f[self.hub])

    def solve(self, guess: np.ndarray, theta: float, rtol: float = 1e-9) -> tuple[np.ndarray, np.ndarray, int]:
        """Equilibrium at the hub rotation theta (rad) by Newton from `guess` with a backtracking line search;
        the displacement (m), the internal forces (N/m) and the iterations."""
        u = self.with_hub(guess, theta)
        f = self.forces(u)
        for iteration in range(40):
            r = f[self.free]
            if iteration and np.linalg.norm(r) < rtol * np.linalg.norm(f[self.hub.ravel()]):
                return u, f, iteration
            k = tangent_stiffness.assemble(self.basis, u=self.basis.interpolate(u), mu=self.mu)
            factor = Pardiso(sp.triu(k[self.free][:, self.free]).tocsr(), indefinite=True)
            step = -factor.solve(r)
            factor.close()
            alpha, norm = 1.0, np.linalg.norm(r)
            while alpha > 1e-3:
                trial = u.copy()
                trial[self.free] += alpha * step
                f_trial = self.forces(trial)
                if np.linalg.norm(f_trial[self.free]) < norm:
                    break
                alpha *= 0.5
            u, f = trial, f_trial
        raise RuntimeError(f"the section did not converge at {theta:.4f} rad")

    def linear_torque(self, theta: float) -> float:
        """The hub torque per unit thickness (Nm/m) of linear plane stress (E = 3 mu, nu = 1/2) at theta (rad)."""
        k = linear_elasticity(2.0 * self.mu, self.mu).assemble(self.basis)  # plane stress: lambda* = 2 mu
        u = self.with_hub(np.zeros(self.basis.N), theta)
        u = skfem.solve(*skfem.condense(k, np.zeros(self.basis.N), x=u, I=self.free))  # the whole vector
        return self.torque(np.zeros_like(u), k @ u)


def path_meshes(study: Study, candidates: str, folder: Path) -> Iterator[tuple[Candidate, TetMesh, PathProblem]]:
    """Each candidate of "BEAMSxTHICKNESS,..." (mm) checked, its sweep's path mesh (meshed into `folder`), and the
    parts of its path without contact."""
    for name in candidates.split(","):
        beams, thickness = name.split("x")
        checked, part = study.check(study.candidate(beam_count=int(beams), beam_thickness_mm=float(thickness)))
        mesh = tetrahedralize(study, checked, part, Cache(folder), layers=SolverSettings().path_layers)
        yield checked, mesh, path_problem(mesh, study.material.law, PathSettings())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--candidates", default="8x4,6x8", help="beams x thickness (mm), comma-separated")
    add_docs_option(ap, "section_path")
    args = ap.parse_args()
    study = load_study()
    law = study.material.law
    table = Table(["design", "3D path mesh (dofs)", "section (dofs)", "section at 1e-4 rad against linear plane stress",
                   "thickness matched / part's", "section against 3D at " + " / ".join(f"{r:g}" for r in COMPARED_RAD)
                   + " rad", "at the 3D path's last point (rad: difference)"])
    with tempfile.TemporaryDirectory() as d:
        for checked, mesh, p in path_meshes(study, args.candidates, Path(d)):
            nodes = p.solid.mesh.nodes_m
            section = Section(mesh.points_mm, mesh.boundary_faces, nodes[p.drive.hub, :2], nodes[p.drive.ring, :2],
                              law.shear_modulus_Pa)
            t0 = time.perf_counter()
            path = rotation_path(mesh, law, study.load_cases.impact_torque_Nm, PathSettings())
            t3d = time.perf_counter() - t0
            u, f, _ = section.solve(np.zeros(section.basis.N), ROTATION_CHECK_RAD)
            linear = section.linear_torque(ROTATION_CHECK_RAD)
            print(f"\n{checked.name}: section at {ROTATION_CHECK_RAD:g} rad {section.torque(u, f):.6g} Nm/m, linear "
                  f"plane stress {linear:.6g} Nm/m ({section.torque(u, f) / linear - 1:+.1e}); 3D path {t3d:.0f} s, "
                  f"ends ({path.stop_reason}) at {path.stop_rotation_rad:.4f} rad", flush=True)
            height_m = np.ptp(mesh.points_mm[:, 2]) * MM
            check = section.torque(u, f) / linear - 1.0
            history, thickness_m, t0 = [(0.0, 0.0 * u), (ROTATION_CHECK_RAD, u)], None, time.perf_counter()
            thetas, differences = [], []
            for point in path.points[1:]:
                theta = point.rotation_rad
                (ta, ua), (tb, ub) = history[-2:]
                u, f, iterations = section.solve(ub + (ub - ua) * (theta - tb) / (tb - ta), theta)
                history.append((theta, u))
                thickness_m = thickness_m or point.torque_Nm / section.torque(u, f)
                torque = section.torque(u, f) * thickness_m
                print(f"  {theta:.4f} rad: 3D {point.torque_Nm:.5g} Nm, section {torque:.5g} Nm "
                      f"({torque / point.torque_Nm - 1:+.2%}), {iterations} Newton iterations", flush=True)
                thetas.append(theta)
                differences.append(torque / point.torque_Nm - 1.0)
            print(f"  section: {time.perf_counter() - t0:.0f} s (scikit-fem forms, full Newton)")
            at = [f"{np.interp(r, thetas, differences):+.2%}" if r <= thetas[-1] else "-" for r in COMPARED_RAD]
            table.add(checked.name, f"{p.system.free.size * 3:,}", f"{section.free.size:,}", f"{check:+.1e}",
                      f"{thickness_m / height_m:.4f}", " / ".join(at), f"{thetas[-1]:.4f}: {differences[-1]:+.2%}")
    settings = (f"Study {study.name}; 3D: the sweep's path mesh, no contact forces, to where the gap closes; section: "
                "plane stress, incompressible neo-Hooke at the material's mu, P2 triangles of the path mesh's top face, "
                "thickness matched at the first point")
    print(f"machine: {machine()}\n{settings}\n{table.markdown()}")
    if args.docs:
        write_fragment("section_path", table, settings)


if __name__ == "__main__":
    main()
