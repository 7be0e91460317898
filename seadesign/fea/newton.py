"""Newton's method for the equilibrium of a hyperelastic body (`fea.equilibrium`): quasi-Newton updates
between refactorizations and a backtracking line search on the energy."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from seadesign.errors import NotPositiveDefinite
from seadesign.fea.equilibrium import Equilibrium
from seadesign.fea.pardiso import Pardiso

@dataclass(frozen=True)
class NewtonSettings:
    max_iterations: int = 30
    refresh_ratio: float = 0.5  # refactor the tangent when an iteration cuts the residual by less than this
    stall_window: int | None = None  # give up ("failed") when the residual has not halved over this many
    # iterations (`stalled`); None: only `max_iterations` ends a solve


@dataclass(frozen=True)
class NewtonResult:
    """The last iterate u (m), its internal forces (N; None when they could not be evaluated), the residual
    norms (N) of the iterations and the status: "converged", "unstable" (a tangent that is not positive
    definite), "failed", or "penetrating" (equilibrium, but contact the multiplier updates could not bring within
    its tolerance: a pair penetrating, or pressed across an open gap; `gap_error_m` says how far)."""

    u: np.ndarray
    forces: np.ndarray | None
    residual_norms: list[float]
    status: str
    gap_error_m: float = 0.0
    augmentations: int = 0


def newton_augmented(system: Equilibrium, u0: np.ndarray, settings: NewtonSettings = NewtonSettings()) -> NewtonResult:
    """`newton` with the contact pairs searched at u0 and held (the contact search once an increment); then, while
    a pair under pressure penetrates, or is held open by its multiplier, further than the contact's tolerance
    (`FrictionlessContact.gap_error_m`), Uzawa's update of the contact multipliers and
    `newton` again: the augmented Lagrangian. Penetration is also measured on the pairs searched afresh at the
    solution; where those penetrate beyond the tolerance (a point the held pairs missed), they join the held ones
    (which stay: a point that slid out of its facet's prism keeps its plane until the next increment, so that
    the assignment cannot cycle).
    The residual norms of all the solves; status "penetrating" when `max_augmentations` rounds did not bring the
    penetration within the tolerance."""
    contact = system.contact
    if contact is not None:
        contact.assignment = contact.search(u0)
    result = newton(system, u0, settings)
    if contact is None or result.status != "converged":
        return result
    norms, tol = list(result.residual_norms), contact.settings.penetration_tol_mm * 1e-3
    for k in range(contact.settings.max_augmentations + 1):
        fresh = contact.search(result.u)
        missed = contact.gap_error_m(result.u, contact.new_pairs(fresh)) > tol
        if missed:
            contact.assignment = contact.with_pairs(fresh)
        depth = contact.gap_error_m(result.u)
        if depth <= tol:
            return NewtonResult(result.u, result.forces, norms, "converged", depth, k)
        if k == contact.settings.max_augmentations:
            break
        if not missed:
            contact.augment(result.u)
        result = newton(system, result.u, settings)
        norms += result.residual_norms
        if result.status != "converged":
            return NewtonResult(result.u, result.forces, norms, result.status, depth, k + 1)
    return NewtonResult(result.u, result.forces, norms, "penetrating", depth, contact.settings.max_augmentations)


def newton(system: Equilibrium, u0: np.ndarray, settings: NewtonSettings = NewtonSettings()) -> NewtonResult:
    """Equilibrium of the free nodes from the guess u0 (its prescribed nodes already in place).

    The tangent is refactored only when needed: between refactorizations the tangent last factored (the
    previous converged state's, or after a cut-back the rejected attempt's) is corrected by BFGS updates
    from the iterations since (Matthies and Strang's quasi-Newton method for finite elements). It is
    refactored at the current iterate when an iteration cuts the residual by less than `refresh_ratio`,
    or its direction finds no descent. A backtracking line search on the energy guards every step."""
    u = u0.copy()
    norms: list[float] = []
    try:
        f = system.forces(u)
    except FloatingPointError:
        return NewtonResult(u, None, norms, "failed")
    r = system.residual(f)
    fresh = False  # the held factorization is of the current iterate
    refresh = system.pardiso is None or not system.pardiso.alive
    updates: list[tuple[np.ndarray, np.ndarray, float]] = []  # BFGS pairs (s, y, 1 / y.s) since the factorization
    for _ in range(settings.max_iterations):
        norms.append(float(np.linalg.norm(r)))
        if system.converged(f, norms[-1]):
            return NewtonResult(u, f, norms, "converged")
        if stalled(norms, settings.stall_window):
            return NewtonResult(u, f, norms, "failed")
        if refresh and not fresh:
            try:
                system.factor(u)
            except NotPositiveDefinite:
                return NewtonResult(u, f, norms, "unstable")
            fresh, updates = True, []
        direction = -_bfgs_solve(system.pardiso, r, updates).reshape(-1, 3)
        trial, f1 = _line_search(system, u, r, direction, norms[-1])
        if trial is None:
            if fresh:
                return NewtonResult(u, f, norms, "failed")
            refresh = True
            norms.pop()
            continue
        r1 = system.residual(f1)
        step, change = (trial[system.free] - u[system.free]).ravel(), r1 - r
        curvature = float(step @ change)
        if curvature > 0:
            updates.append((step, change, 1.0 / curvature))
        refresh = float(np.linalg.norm(r1)) > settings.refresh_ratio * norms[-1]
        u, f, r, fresh = trial, f1, r1, False
    norms.append(float(np.linalg.norm(r)))
    return NewtonResult(u, f, norms, "converged" if system.converged(f, norms[-1]) else "failed")


def stalled(norms: list[float], window: int | None) -> bool:
    """Whether the last residual norm is above half the one `window` iterations before (None: never): Newton
    wandering, as where a creasing notch makes the tangent indefinite, rather than converging, if only linearly."""
    return window is not None and len(norms) > window and norms[-1] > 0.5 * norms[-1 - window]


def _bfgs_solve(factorization: Pardiso, r: np.ndarray, updates: list[tuple[np.ndarray, np.ndarray, float]]) -> np.ndarray:
    """H r with H the inverse of the factored tangent corrected by the BFGS pairs (the two-loop recursion)."""
    q, alphas = r.copy(), []
    for s, y, rho in reversed(updates):
        alphas.append(rho * float(s @ q))
        q -= alphas[-1] * y
    z = factorization.solve(q)
    for (s, y, rho), alpha in zip(updates, reversed(alphas)):
        z += (alpha - rho * float(y @ z)) * s
    return z


def _line_search(system: Equilibrium, u: np.ndarray, r: np.ndarray, du: np.ndarray,
                 norm: float) -> tuple[np.ndarray | None, np.ndarray | None]:
    """u + alpha du (free nodes): alpha 1 or else 1/2 if its residual norm is below `norm`; else the first alpha in
    1, 1/2, ... 1/1000 whose residual norm is below `norm` or whose energy falls as Armijo asks; (None, None) when
    none does. The residual is tried at half a step before the energy at the full one: a full step that presses
    contact pairs deep into their facets lowers the energy but multiplies the residual, and its successor then
    needs a new factorization."""
    trials: dict[float, tuple[np.ndarray, np.ndarray | None, bool]] = {}  # alpha -> (u, forces, residual falls)

    def at(alpha: float) -> tuple[np.ndarray, np.ndarray | None, bool]:
        if alpha not in trials:
            trial = u.copy()
            trial[system.free] += alpha * du
            try:
                f1 = system.forces(trial)
                trials[alpha] = (trial, f1, bool(np.linalg.norm(system.residual(f1)) < norm))
            except FloatingPointError:  # an element inverted: shorten the step
                trials[alpha] = (trial, None, False)
        return trials[alpha]

    for alpha in (1.0, 0.5):
        trial, f1, falls = at(alpha)
        if falls:
            return trial, f1
    e0, slope = None, float(r @ du.ravel())
    alpha = 1.0
    while alpha > 1e-3:
        trial, f1, falls = at(alpha)
        if falls:
            return trial, f1
        if f1 is not None:
            try:
                e0 = system.energy(u) if e0 is None else e0
                if system.energy(trial) <= e0 + 1e-4 * alpha * slope:
                    return trial, f1
            except FloatingPointError:
                pass
        alpha *= 0.5
    return None, None
