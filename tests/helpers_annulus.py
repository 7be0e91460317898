"""A structured tetrahedral mesh of a flat annulus with nodes exactly on its circles, and the
closed-form torsion solution used as the independent reference."""

from __future__ import annotations

import itertools
import math

import numpy as np

from seadesign.mesh.tetmesh import build_tetmesh
from seadesign.design.interfaces import Interfaces


def annulus_interfaces(a_mm: float, b_mm: float, h_mm: float) -> Interfaces:
    """Interfaces of a plain annulus: the bore (r = a) is the hub side, the outer face (r = b) the ring side."""
    return Interfaces(
        hub_holes=(),
        ring_holes=(),
        bore_radius_mm=a_mm,
        hub_radius_mm=a_mm,
        ring_inner_radius_mm=b_mm,
        ring_outer_radius_mm=b_mm,
        thickness_mm=h_mm,
    )


def annulus_mesh(a_mm: float, b_mm: float, h_mm: float, n_r: int, n_theta: int, n_z: int):
    """Kuhn-split hexahedral grid in (r, theta, z); radial spacing geometric (finer at the bore)."""
    r = a_mm * (b_mm / a_mm) ** np.linspace(0.0, 1.0, n_r + 1)
    th = np.linspace(0.0, 2 * np.pi, n_theta, endpoint=False)
    z = np.linspace(0.0, h_mm, n_z + 1)
    R, T, Z = np.meshgrid(r, th, z, indexing="ij")
    pts = np.stack([R * np.cos(T), R * np.sin(T), Z], axis=-1).reshape(-1, 3)

    def nid(i, j, k):
        return (i * n_theta + (j % n_theta)) * (n_z + 1) + k

    i, j, k = np.meshgrid(np.arange(n_r), np.arange(n_theta), np.arange(n_z), indexing="ij")
    i, j, k = i.ravel(), j.ravel(), k.ravel()
    tets = []
    for perm in itertools.permutations(range(3)):
        off = np.zeros(3, dtype=int)
        path = [nid(i, j, k)]
        for axis in perm:
            off[axis] += 1
            path.append(nid(i + off[0], j + off[1], k + off[2]))
        tets.append(np.stack(path, axis=1))
    tets = np.concatenate(tets)
    return build_tetmesh(pts, tets, annulus_interfaces(a_mm, b_mm, h_mm), tol_mm=1e-6 * b_mm)


def annulus_k_Nm_per_rad(a_mm: float, b_mm: float, h_mm: float, youngs_modulus_Pa: float, poisson_ratio: float) -> float:
    """k = 4 pi G h a^2 b^2 / (b^2 - a^2) (lengths converted mm -> m)."""
    a, b, h = a_mm * 1e-3, b_mm * 1e-3, h_mm * 1e-3
    g = youngs_modulus_Pa / (2 * (1 + poisson_ratio))
    return 4 * math.pi * g * h * a**2 * b**2 / (b**2 - a**2)


def annulus_peak_shear_Pa(a_mm: float, h_mm: float, torque_Nm: float) -> float:
    """Peak shear stress T / (2 pi a^2 h) at the bore."""
    a, h = a_mm * 1e-3, h_mm * 1e-3
    return torque_Nm / (2 * math.pi * a**2 * h)


# Rivlin's circular shear of a neo-Hookean annulus (radii A_MM, B_MM, height H_MM, modulus E in Pa), plane strain
A_MM, B_MM, H_MM, E = 10.0, 20.0, 4.0, 12e6


def circular_shear(n_r: int, n_theta: int, nu: float, formulation: str):
    """(path, T1, mu): the path to the torque T1 (Nm) of 1 rad in Rivlin's solution, faces held axially (u_z = 0,
    plane strain), on an n_r x n_theta annulus; mu the shear modulus (Pa)."""
    from seadesign.design.materials import Hyperelastic
    from seadesign.fea.rotation_path import PathSettings, rotation_path
    from seadesign.fea.torsion import MM

    mesh = annulus_mesh(A_MM, B_MM, H_MM, n_r, n_theta, 1)
    z = mesh.points_mm[mesh.boundary_faces][:, :, 2]
    faces = mesh.boundary_faces[np.all(z < 1e-6, axis=1) | np.all(z > H_MM - 1e-6, axis=1)]
    mu = E / (2 * (1 + nu))
    t1 = 4 * np.pi * mu * H_MM * MM / ((A_MM * MM) ** -2 - (B_MM * MM) ** -2)  # T at phi(a) = 1 rad
    path = rotation_path(mesh, Hyperelastic.from_linear(E, nu), 1.001 * t1, PathSettings(max_step_rad=0.25),
                         axially_held_faces=faces, formulation=formulation)
    return path, t1, mu


def radial_drift(path) -> np.ndarray:
    """|r' - r| of every vertex over the hub's arc at the last rotation (dimensionless)."""
    from seadesign.fea.torsion import MM

    x0, u = path.emesh.nodes_m[: path.emesh.n_vertices], path.displacement_m[: path.emesh.n_vertices]
    dr = np.hypot(*(x0 + u)[:, :2].T) - np.hypot(*x0[:, :2].T)
    return np.abs(dr) / (A_MM * MM * path.points[-1].rotation_rad)
