"""The servo's boundary condition on the spring: the hub's coupled surface nodes follow x' = R(theta) x
exactly (rotation about the z axis, no translation, no tilt) and the ring's coupled nodes are held.
The reaction torque is the moment about z of the internal forces on the hub nodes. SI units; the mesh
arrives in mm."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from seadesign.errors import SolverError
from seadesign.fea.elements import ElementMesh
from seadesign.fea.torsion import default_boundaries, surface_nodes
from seadesign.mesh.tetmesh import TetMesh


def moment_z(x: np.ndarray, f: np.ndarray) -> float:
    """z component of sum x x f (Nm) over rows of positions x (m) and forces f (N)."""
    return float(np.sum(x[:, 0] * f[:, 1] - x[:, 1] * f[:, 0]))


@dataclass(frozen=True)
class HubRotation:
    """The driven hub nodes and the held ring nodes of an element mesh (node ids), and the rest positions (m)."""

    nodes_m: np.ndarray
    hub: np.ndarray
    ring: np.ndarray

    @classmethod
    def on(cls, mesh: TetMesh, emesh: ElementMesh, hub_boundaries: list[str] | None = None,
           ring_boundaries: list[str] | None = None) -> "HubRotation":
        """The nodes of the named boundaries of `mesh` (the study's interfaces unless named) in `emesh`."""
        default_hub, default_ring = default_boundaries(mesh)

        def nodes(names: list[str]) -> np.ndarray:
            mesh.boundary_nodes(names)  # a clear error when one is absent
            return surface_nodes(emesh, np.concatenate([mesh.boundary_faces[mesh.boundaries[n]] for n in names]))

        hub, ring = nodes(hub_boundaries or default_hub), nodes(ring_boundaries or default_ring)
        if np.intersect1d(hub, ring).size:
            raise SolverError("the hub and the ring surfaces share nodes; they must be separate interfaces")
        return cls(emesh.nodes_m, hub, ring)

    @property
    def prescribed(self) -> np.ndarray:
        """Hub and ring nodes, sorted."""
        return np.union1d(self.hub, self.ring)

    def displacement(self, theta: float) -> np.ndarray:
        """(n_hub, 3) displacement (m) of the hub nodes at rotation theta (rad)."""
        x, y = self.nodes_m[self.hub, 0], self.nodes_m[self.hub, 1]
        c, s = np.cos(theta), np.sin(theta)
        return np.column_stack([(c - 1) * x - s * y, s * x + (c - 1) * y, np.zeros_like(x)])

    def velocity(self, theta: float) -> np.ndarray:
        """d(hub displacement)/dtheta (m/rad)."""
        x, y = self.nodes_m[self.hub, 0], self.nodes_m[self.hub, 1]
        c, s = np.cos(theta), np.sin(theta)
        return np.column_stack([-s * x - c * y, c * x - s * y, np.zeros_like(x)])

    def torque(self, u: np.ndarray, f: np.ndarray) -> float:
        """Reaction torque about z (Nm) that holds the hub: sum of x' x f over the hub nodes (f: internal, N)."""
        return moment_z(self.nodes_m[self.hub] + u[self.hub], f[self.hub])
