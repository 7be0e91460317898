"""The equilibrium of a solid's free nodes with the others prescribed: the out-of-balance forces,
the convergence test, and the tangent's factorization with its inertia. Newton (`fea.newton`)
works on this object; the path (`fea.rotation_path`) prescribes the hub's rotation through it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from seadesign.errors import NotPositiveDefinite
from seadesign.fea.assembly import PairPattern, add_pair_blocks
from seadesign.fea.contact import FrictionlessContact
from seadesign.fea.finite_strain import Solid
from seadesign.fea.pardiso import Pardiso


@dataclass
class Equilibrium:
    """A solid, and its frictionless self-contact if any, whose nodes outside `free` are prescribed; `reaction`
    are the nodes whose forces set the convergence scale (the driven ones)."""

    solid: Solid
    free: np.ndarray
    node_index: np.ndarray  # mesh node -> block row of the tangent, -1 for a prescribed node
    dof_free: np.ndarray  # (n_free, 3) 1.0 for a free degree of freedom of a free node, 0.0 for one held at zero
    reaction: np.ndarray
    force_rtol: float  # residual norm over the norm of the reaction forces
    pattern: PairPattern  # where the tangent's element blocks land (free nodes only)
    contact: FrictionlessContact | None = None
    pardiso: Pardiso | None = None  # the factorization last made
    factorizations: int = 0

    @classmethod
    def of(cls, solid: Solid, prescribed: np.ndarray, reaction: np.ndarray, force_rtol: float,
           held_z: np.ndarray | None = None, contact: FrictionlessContact | None = None) -> "Equilibrium":
        """Free nodes: all but `prescribed`; `held_z`: nodes whose u_z stays zero (an analytical test's plane)."""
        n = len(solid.mesh.nodes_m)
        free = np.setdiff1d(np.arange(n), prescribed)
        index = np.full(n, -1, dtype=np.int64)
        index[free] = np.arange(len(free))
        dof_free = np.ones((len(free), 3))
        if held_z is not None:
            held = index[held_z]
            dof_free[held[held >= 0], 2] = 0.0
        return cls(solid, free, index, dof_free, reaction, force_rtol,
                   PairPattern.of(solid.mesh.elements, solid.mesh.order, index, len(free)), contact)

    def forces(self, u: np.ndarray) -> np.ndarray:
        """(N, 3) internal forces (N) at u: the solid's and the contact's."""
        f = self.solid.forces(u)
        return f if self.contact is None else f + self.contact.forces(u)

    def energy(self, u: np.ndarray) -> float:
        """Stored energy (J) at u: the strain energy and the contact's."""
        e = self.solid.energy(u)
        return e if self.contact is None else e + self.contact.energy(u)

    def tangent_product(self, u: np.ndarray, v: np.ndarray, rows: np.ndarray | None = None) -> np.ndarray:
        """(N, 3) tangent at u times the nodal vector v (N); `rows`: see `Solid.tangent_product`."""
        f = self.solid.tangent_product(u, v, rows)
        if self.contact is not None:
            nodes, blocks = self.contact.tangent_blocks(u)
            np.add.at(f, nodes, np.einsum("pabij,pbj->pai", blocks, v[nodes]))
        return f

    def residual(self, f: np.ndarray) -> np.ndarray:
        """The out-of-balance forces (N) on the free degrees of freedom, flattened."""
        return (f[self.free] * self.dof_free).ravel()

    def converged(self, f: np.ndarray, residual_norm: float) -> bool:
        """Whether the out-of-balance force is within the tolerance of the reaction forces."""
        return residual_norm <= self.force_rtol * max(float(np.linalg.norm(f[self.reaction])), 1e-12)

    def factor(self, u: np.ndarray) -> Pardiso:
        """LDL^T factorization of the free-node tangent at u; NotPositiveDefinite when its inertia counts a
        negative eigenvalue (the state has lost stability) and no contact carries pressure: with contact the
        consistent tangent may be indefinite at a crease, and `stable_factor` judges. The inertia is exact, where a
        Cholesky factorization near a singular point may or may not meet its negative pivot."""
        pressed = self._factor(u, geometric=True)
        if not pressed and self.pardiso.inertia()[1] > 0:
            raise NotPositiveDefinite("the tangent stiffness has a negative eigenvalue")
        return self.pardiso

    def stable_factor(self, u: np.ndarray) -> Pardiso:
        """`factor` at a converged state u, which must be stable: NotPositiveDefinite when the tangent (the energy's
        Hessian) has a negative eigenvalue and, where contact carries pressure, so has the tangent with the
        contact's normal stiffness only (see `FrictionlessContact.tangent_blocks`: buckling of the part with its
        contacts as constraints, where the pressure's geometric part alone would count a crease). A positive
        definite tangent is a strict minimum of the energy, stable whatever the contact; only where it is not does
        the second tangent judge, and the tangent is factored again for the path's direction."""
        pressed = self._factor(u, geometric=True)
        if self.pardiso.inertia()[1] == 0:
            return self.pardiso
        if pressed:
            self._factor(u, geometric=False)
        if not pressed or self.pardiso.inertia()[1] > 0:
            raise NotPositiveDefinite("the tangent stiffness has a negative eigenvalue")
        return self.factor(u)

    def _factor(self, u: np.ndarray, geometric: bool) -> bool:
        """Factor the tangent at u (the contact's geometric part if `geometric`); whether contact presses there
        (a pair without pressure has a zero block)."""
        k = self.solid.tangent(u, self.pattern)
        pressed = False
        if self.contact is not None:
            nodes, blocks = self.contact.tangent_blocks(u, geometric)
            pressed = bool(np.any(blocks))
            if len(nodes):
                k = add_pair_blocks(k, self.node_index, nodes, blocks)
        self._hold(k)
        k = k.matrix()
        if self.pardiso is not None and self.pardiso.alive and self.pardiso.same_pattern(k):
            self.pardiso.refactor(k)
        else:
            self.close()
            self.pardiso = Pardiso(k, indefinite=True)
        self.factorizations += 1
        return pressed

    def _hold(self, k) -> None:
        """Held degrees of freedom: zero rows and columns, unit diagonal (in place)."""
        if not self.dof_free.all():
            m = self.dof_free
            k.values[:] *= m[k.rows][:, :, None] * m[k.cols][:, None, :]
            diag = k.rows == k.cols
            k.values[diag] += np.eye(3) * (1.0 - m[k.rows[diag]])[:, None, :]

    def close(self) -> None:
        if self.pardiso is not None:
            self.pardiso.close()
