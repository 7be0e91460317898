"""One stiffness problem for both load cases: a unit torque about +z on the rigidly coupled hub
surface with the ring surface held. Any other torque is this solution scaled; swapping which
side is held only adds a rigid-body motion (same strains, stresses and interface forces).

Input mesh in mm; everything inside is SI (m, N, Pa, rad).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from seadesign.fea.assembly import UpperBlocks, nodal_forces, stiffness_upper
from seadesign.fea.couplings import RigidCoupling, couple
from seadesign.fea.elements import ElementMesh, element_mesh, midside_nodes
from seadesign.fea.linsolve import SPDFactorization
from seadesign.mesh.tetmesh import TetMesh

MM = 1e-3  # m per mm


@dataclass(frozen=True)
class UnitTorsion:
    """Response per 1 Nm of hub torque about +z (ring held).

    displacement_m: (N, 3) nodal displacement in m/Nm; hub_motion: (6,) reference point
    translation (m/Nm) and rotation (rad/Nm); nodal_force_N: (N, 3) internal nodal forces K u in
    N/Nm on the coupled and held nodes (the coupling and support reactions; zero elsewhere).
    """

    emesh: ElementMesh
    displacement_m: np.ndarray
    hub_motion: np.ndarray
    nodal_force_N: np.ndarray
    ref_m: np.ndarray
    hub_groups: dict[str, np.ndarray]
    ring_nodes: np.ndarray
    n_dofs: int
    timings_s: dict = field(default_factory=dict)


def surface_nodes(emesh: ElementMesh, faces: np.ndarray) -> np.ndarray:
    """All element nodes on the given linear facets (vertices, plus edge midpoints for order 2)."""
    nodes = [faces.ravel()]
    if emesh.order == 2:
        for i, j in ((0, 1), (1, 2), (2, 0)):
            nodes.append(midside_nodes(emesh, faces[:, i], faces[:, j]))
    return np.unique(np.concatenate(nodes))


def default_boundaries(mesh: TetMesh) -> tuple[list[str], list[str]]:
    """Coupled surfaces: hub bolt-hole walls (else the bore); ring bolt-hole walls (else the outer face)."""
    names = mesh.boundaries
    hub = sorted((n for n in names if n.startswith("hub_hole_")), key=lambda s: int(s.rsplit("_", 1)[1]))
    ring = sorted((n for n in names if n.startswith("ring_hole_")), key=lambda s: int(s.rsplit("_", 1)[1]))
    return hub or ["bore"], ring or ["outer"]


@dataclass(frozen=True)
class TorsionProblem:
    """The unit torsion problem assembled: the coupled surfaces and the condensed stiffness (N/m, N/rad, Nm/rad in
    its translation and rotation entries), with the seconds its set-up and assembly took."""

    emesh: ElementMesh
    coupling: RigidCoupling
    stiffness: UpperBlocks
    hub_groups: dict[str, np.ndarray]
    hub_nodes: np.ndarray
    ring_nodes: np.ndarray
    ref_m: np.ndarray
    setup_s: float
    assembly_s: float

    def unit_load(self) -> np.ndarray:
        """The condensed load of 1 Nm about +z on the hub's reference point."""
        rhs = np.zeros(3 * self.stiffness.n)
        rhs[self.coupling.ref_dofs[5]] = 1.0
        return rhs


def torsion_problem(mesh: TetMesh, youngs_modulus_Pa: float, poisson_ratio: float,
                    hub_boundaries: list[str] | None = None, ring_boundaries: list[str] | None = None,
                    order: int = 2) -> TorsionProblem:
    """Couple the hub surfaces to a reference point on the axis at mid-thickness (its six dofs free), hold the
    ring surfaces, and assemble and condense the stiffness (defaults: `default_boundaries`)."""
    t0 = time.perf_counter()
    default_hub, default_ring = default_boundaries(mesh)
    hub_boundaries = hub_boundaries or default_hub
    ring_boundaries = ring_boundaries or default_ring
    emesh = element_mesh(mesh.points_mm * MM, mesh.tets, order)
    hub_groups = {}
    for name in hub_boundaries:
        mesh.boundary_nodes([name])  # raises a clear error when absent
        hub_groups[name] = surface_nodes(emesh, mesh.boundary_faces[mesh.boundaries[name]])
    hub_nodes = np.unique(np.concatenate(list(hub_groups.values())))
    mesh.boundary_nodes(ring_boundaries)
    ring_faces = np.concatenate([mesh.boundary_faces[mesh.boundaries[n]] for n in ring_boundaries])
    ring_nodes = surface_nodes(emesh, ring_faces)
    z = mesh.points_mm[:, 2]
    ref_m = np.array([0.0, 0.0, 0.5 * (z.min() + z.max()) * MM])
    t1 = time.perf_counter()

    cpl = couple(emesh.nodes_m, hub_nodes, ring_nodes, ref_m)
    k = cpl.condense(stiffness_upper(emesh, youngs_modulus_Pa, poisson_ratio, cpl.node_index, cpl.n_rows))
    return TorsionProblem(emesh, cpl, k, hub_groups, hub_nodes, ring_nodes, ref_m, t1 - t0, time.perf_counter() - t1)


def solve_unit_torsion(
    mesh: TetMesh,
    youngs_modulus_Pa: float,
    poisson_ratio: float,
    hub_boundaries: list[str] | None = None,
    ring_boundaries: list[str] | None = None,
    order: int = 2,
    linear_solver: str = "pardiso",
) -> UnitTorsion:
    """Assemble, couple, factor once and solve for 1 Nm on the hub (`torsion_problem`)."""
    problem = torsion_problem(mesh, youngs_modulus_Pa, poisson_ratio, hub_boundaries, ring_boundaries, order)
    emesh, cpl, k = problem.emesh, problem.coupling, problem.stiffness
    t2 = time.perf_counter()

    precision = "mixed" if linear_solver == "pardiso" else "double"  # PARDISO: half the factors' memory
    fact = SPDFactorization(k.matrix(), backend=linear_solver, precision=precision)
    t3 = time.perf_counter()

    q = fact.solve(problem.unit_load())
    fact.close()
    u = cpl.displacements(q)
    f = nodal_forces(emesh, u, youngs_modulus_Pa, poisson_ratio, np.union1d(problem.hub_nodes, problem.ring_nodes))
    t4 = time.perf_counter()
    return UnitTorsion(
        emesh=emesh,
        displacement_m=u,
        hub_motion=q[cpl.ref_dofs],
        nodal_force_N=f,
        ref_m=problem.ref_m,
        hub_groups=problem.hub_groups,
        ring_nodes=problem.ring_nodes,
        n_dofs=3 * k.n,
        timings_s={"setup": problem.setup_s, "assembly": problem.assembly_s, "factorization": t3 - t2,
                   "solve": t4 - t3},
    )
