"""The study's two load cases from one factorization, as typed results (`fea.results`).

stall: stall torque on the hub (horn side), ring held -> rotation, bearing displacement, k.
impact: impact torque on the ring (backplate side), hub held -> reactions at the hub bolts.
The impact case equals the stall problem with hub torque -T_impact plus a rigid-body motion
(which changes no strain, stress or interface force), so both are scalings of one solve.
Mesh coordinates are mm; all physics SI; outputs converted where the key says so (_mm, _MPa).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from seadesign.errors import SolverError
from seadesign.fea.results import ImpactResult, LinearResults, PeakStresses, SolveStats, StallResult, StressPeak
from seadesign.fea.stress import invariants, project_to_nodes, vertex_stresses
from seadesign.fea.torsion import MM, UnitTorsion, solve_unit_torsion
from seadesign.mesh.tetmesh import TetMesh

STRESS_NAMES = ("von_mises", "principal_1", "principal_3", "max_shear")


@dataclass(frozen=True)
class Analysis:
    """Everything one solve produced: the unit-torque fields and the load-case numbers."""

    unit: UnitTorsion
    stress_per_Nm_Pa: np.ndarray  # (N, 6) nodal stress per 1 Nm of hub torque, Voigt xx yy zz xy yz zx
    hub_torque_Nm: dict[str, float]  # load case -> equivalent hub torque (stall: +T, impact: -T)
    results: LinearResults

    def displacement_m(self, case: str) -> np.ndarray:
        """(N, 3) displacement in m (impact: relative to the held hub, rigid motion removed)."""
        u = self.unit.displacement_m * self.hub_torque_Nm[case]
        if case == "impact":
            u = u - self._rigid_hub(self.hub_torque_Nm[case])
        return u

    def stress_Pa(self, case: str) -> np.ndarray:
        """(N, 6) nodal stress in Pa."""
        return self.stress_per_Nm_Pa * self.hub_torque_Nm[case]

    def _rigid_hub(self, torque_Nm: float) -> np.ndarray:
        m = self.unit.hub_motion * torque_Nm
        d = self.unit.emesh.nodes_m - self.unit.ref_m
        return m[:3] + np.cross(m[3:], d)


def _stress_peaks(voigt_Pa: np.ndarray, nodes_mm: np.ndarray, yield_strength_Pa: float) -> PeakStresses:
    """Peak of each STRESS_NAMES measure (the minimum of principal_3), where it is, and the safety factor."""
    inv = invariants(voigt_Pa)
    out = {}
    for name in STRESS_NAMES:
        field = inv[name]
        i = int(np.argmin(field)) if name == "principal_3" else int(np.argmax(field))
        x, y, z = (float(c) for c in nodes_mm[i])
        out[f"{name}_{'min' if name == 'principal_3' else 'max'}"] = StressPeak(float(field[i] * 1e-6), x, y, z)
    return PeakStresses(**out, safety_factor=yield_strength_Pa / (out["von_mises_max"].MPa * 1e6))


def _results(unit: UnitTorsion, stress_per_Nm: np.ndarray, torque: dict[str, float], yield_strength_Pa: float,
             bearing_radius_mm: float, stats: SolveStats) -> LinearResults:
    """The load-case numbers of one unit solve at the given hub torques (stall +T, impact -T)."""
    theta = float(unit.hub_motion[5])
    nodes_mm = unit.emesh.nodes_m / MM
    f = unit.nodal_force_N
    ring = unit.ring_nodes
    ring_torque = float(np.sum(unit.emesh.nodes_m[ring, 0] * f[ring, 1] - unit.emesh.nodes_m[ring, 1] * f[ring, 0]))
    equilibrium = abs(ring_torque + 1.0)  # reaction torque must cancel the applied 1 Nm

    # bearing circle at the reference plane, moving with the rigid hub
    phi = np.linspace(0.0, 2 * np.pi, 720, endpoint=False)
    circle = np.column_stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)]) * bearing_radius_mm * MM
    bearing_per_Nm = float(np.linalg.norm(unit.hub_motion[:3] + np.cross(unit.hub_motion[3:], circle), axis=1).max())

    bolt = [np.linalg.norm(f[nodes].sum(axis=0)) for nodes in unit.hub_groups.values()]
    hub_nodes = np.unique(np.concatenate(list(unit.hub_groups.values())))
    peak_nodal = float(np.linalg.norm(f[hub_nodes], axis=1).max())

    t_stall, t_impact = torque["stall"], -torque["impact"]
    stresses = {case: _stress_peaks(stress_per_Nm * t, nodes_mm, yield_strength_Pa) for case, t in torque.items()}
    stall = StallResult(torque_Nm=t_stall, rotation_rad=t_stall * theta,
                        bearing_displacement_mm=t_stall * bearing_per_Nm / MM, stresses=stresses["stall"])
    impact = ImpactResult(
        torque_Nm=t_impact, reaction_per_bolt_N=t_impact * float(max(bolt)),
        reaction_per_bolt_min_N=t_impact * float(min(bolt)), bolt_count=float(len(bolt)),
        peak_nodal_reaction_N=t_impact * peak_nodal, stresses=stresses["impact"])
    return LinearResults(k_Nm_per_rad=1.0 / theta, equilibrium_rel_error=equilibrium, stall=stall, impact=impact,
                         stats=stats)


def _stats(unit: UnitTorsion, mesh: TetMesh, order: int, t_stress: float) -> SolveStats:
    t = unit.timings_s
    return SolveStats(
        element_order=float(order), dofs=float(unit.n_dofs), mesh_nodes=float(len(mesh.points_mm)),
        mesh_tets=float(len(mesh.tets)), mesh_min_dihedral_deg=mesh.quality.min_dihedral_deg,
        mesh_max_aspect_ratio=mesh.quality.max_aspect_ratio, time_setup_s=t["setup"], time_assembly_s=t["assembly"],
        time_factorization_s=t["factorization"], time_solve_s=t["solve"], time_stress_s=t_stress)


def analyse(
    mesh: TetMesh,
    youngs_modulus_Pa: float,
    poisson_ratio: float,
    yield_strength_Pa: float,
    stall_torque_Nm: float,
    impact_torque_Nm: float,
    bearing_radius_mm: float,
    order: int = 2,
    hub_boundaries: list[str] | None = None,
    ring_boundaries: list[str] | None = None,
    linear_solver: str = "pardiso",
) -> Analysis:
    """Solve both load cases (see module doc) and keep the fields for export."""
    checks = {
        "youngs_modulus_Pa": youngs_modulus_Pa > 0,
        "poisson_ratio": -1.0 < poisson_ratio < 0.5,
        "yield_strength_Pa": yield_strength_Pa > 0,
        "stall_torque_Nm": stall_torque_Nm > 0,
        "impact_torque_Nm": impact_torque_Nm > 0,
        "bearing_radius_mm": bearing_radius_mm > 0,
    }
    bad = [k for k, ok in checks.items() if not ok]
    if bad:
        raise SolverError(
            f"invalid {', '.join(bad)}: moduli, strength, torques and radius must be positive and "
            "-1 < poisson_ratio < 0.5"
        )
    unit = solve_unit_torsion(mesh, youngs_modulus_Pa, poisson_ratio, hub_boundaries, ring_boundaries, order, linear_solver)
    t0 = time.perf_counter()
    stress = project_to_nodes(unit.emesh, vertex_stresses(unit.emesh, unit.displacement_m, youngs_modulus_Pa, poisson_ratio))
    t_stress = time.perf_counter() - t0

    theta = float(unit.hub_motion[5])
    if not theta > 0:
        raise SolverError(f"hub rotation per Nm is {theta:g} rad; the mesh or its couplings are broken")
    torque = {"stall": float(stall_torque_Nm), "impact": -float(impact_torque_Nm)}
    results = _results(unit, stress, torque, yield_strength_Pa, bearing_radius_mm,
                       _stats(unit, mesh, order, t_stress))
    return Analysis(unit=unit, stress_per_Nm_Pa=stress, hub_torque_Nm=torque, results=results)

