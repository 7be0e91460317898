"""Finite-strain hyperelastic laws in CalculiX's form, as functions of the deformation gradient.

W = sum Cij (I1bar - 3)^i (I2bar - 3)^j + sum_k (J - 1)^(2k) / Dk, with I1bar = J^(-2/3) tr C and
I2bar = J^(-4/3) I2(C) the isochoric invariants (C = F^T F, J = det F). `stress` gives the first
Piola-Kirchhoff stress P = dW/dF (Pa) and `tangent` A = dP/dF (Pa), both vectorised over any
leading axes of F (..., 3, 3). Moduli in Pa, compressibilities in 1/Pa (0: the term is absent).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import NamedTuple

import numpy as np

from seadesign.design.materials import Hyperelastic
from seadesign.fea.kernels import det_inverse_transpose, mooney_rivlin_stress, mooney_rivlin_tangent

_I = np.eye(3)


class _Kinematics:
    """Invariants of F (..., 3, 3); I2 is computed when a law asks for it (Mooney-Rivlin's energy)."""

    def __init__(self, F: np.ndarray) -> None:
        self.F = F
        self.J, self.H = det_and_inverse_transpose(F)  # H = F^-T
        self.I1 = np.einsum("...ij,...ij->...", F, F)

    @cached_property
    def C(self) -> np.ndarray:
        return np.swapaxes(self.F, -1, -2) @ self.F

    @cached_property
    def I2(self) -> np.ndarray:
        return 0.5 * (self.I1**2 - np.sum(self.C * self.C, axis=(-2, -1)))


def det_and_inverse_transpose(F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """det F and F^-T of each F (..., 3, 3) from the cofactors (columns c_i: cof = [c1 x c2, c2 x c0, c0 x c1]);
    FloatingPointError when an element is inverted (det F <= 0)."""
    J, H = det_inverse_transpose(np.ascontiguousarray(F, dtype=float).reshape(-1, 3, 3))
    if np.any(J <= 0):
        raise FloatingPointError("inverted element: det F <= 0")
    return J.reshape(F.shape[:-2]), H.reshape(F.shape)


def volumetric(law: Hyperelastic, J: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The volumetric energy U(J) = sum (J - 1)^(2k) / Dk (J/m^3) and its derivatives U', U'' (Pa)."""
    j = np.asarray(J, dtype=float) - 1.0
    u, du, ddu = np.zeros_like(j), np.zeros_like(j), np.zeros_like(j)
    for k, d in enumerate((law.d1_per_Pa, law.d2_per_Pa, law.d3_per_Pa), start=1):
        if d > 0:
            u = u + j ** (2 * k) / d
            du = du + 2 * k * j ** (2 * k - 1) / d
            ddu = ddu + 2 * k * (2 * k - 1) * j ** (2 * k - 2) / d
    return u, du, ddu


def _isochoric(law: Hyperelastic, i1b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """dW/dI1bar and d2W/dI1bar2 (Pa). These laws are linear in I2bar (dW/dI2bar = C01) with no mixed terms."""
    a = i1b - 3.0
    return law.c10_Pa + 2 * law.c20_Pa * a + 3 * law.c30_Pa * a**2, 2 * law.c20_Pa + 6 * law.c30_Pa * a


def isochoric_energy_density(law: Hyperelastic, F: np.ndarray) -> np.ndarray:
    """The isochoric part of W (J/m^3) at each F (..., 3, 3)."""
    kin = _Kinematics(F)
    a = kin.J ** (-2 / 3) * kin.I1 - 3.0
    w = law.c10_Pa * a + law.c20_Pa * a**2 + law.c30_Pa * a**3
    return w + law.c01_Pa * (kin.J ** (-4 / 3) * kin.I2 - 3.0) if law.c01_Pa else w


def energy_density(law: Hyperelastic, F: np.ndarray) -> np.ndarray:
    """Strain energy per reference volume (J/m^3) at each F (..., 3, 3)."""
    return isochoric_energy_density(law, F) + volumetric(law, np.linalg.det(F))[0]


def _first(kin: _Kinematics) -> tuple[np.ndarray, np.ndarray]:
    """I1bar and dI1bar/dF."""
    j23 = kin.J ** (-2 / 3)
    return j23 * kin.I1, j23[..., None, None] * (2.0 * kin.F - (2 / 3) * kin.I1[..., None, None] * kin.H)


def stress(law: Hyperelastic, F: np.ndarray, pressure_Pa: np.ndarray | None = None) -> np.ndarray:
    """First Piola-Kirchhoff stress P = dW/dF (Pa), shape of F. `pressure_Pa` replaces U'(J) (a mean
    dilatation formulation passes U' of the element's mean J)."""
    if law.c01_Pa:
        return _mooney_rivlin_stress(mooney_rivlin_fields(law, F, pressure_Pa).flat()).reshape(F.shape)
    kin = _Kinematics(F)
    wj = _volumetric_slopes(law, kin.J, pressure_Pa)[0]
    i1b, d1 = _first(kin)
    e = (..., None, None)
    return _isochoric(law, i1b)[0][e] * d1 + (wj * kin.J)[e] * kin.H


def _outer(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[..., :, :, None, None] * b[..., None, None, :, :]


@dataclass(frozen=True)
class I1Tangent:
    """dP/dF of a law in I1bar and J only (neo-Hooke, Yeoh), as five scalar fields (...) in Pa:
    A = delta d_ik d_JL + cross (F_iJ H_kL + H_iJ F_kL) + hh H_iJ H_kL + hx H_iL H_kJ + w11 D_iJ D_kL
    with H = F^-T and D = dI1bar/dF. A caller that contracts A with gradients uses these terms
    directly instead of the 81 components."""

    P: np.ndarray
    F: np.ndarray
    H: np.ndarray
    D: np.ndarray
    delta: np.ndarray
    cross: np.ndarray
    hh: np.ndarray
    hx: np.ndarray
    w11: np.ndarray

    def full(self) -> np.ndarray:
        """A (..., 3, 3, 3, 3)."""
        e4 = (..., None, None, None, None)
        ii = np.einsum("ik,JL->iJkL", _I, _I)
        hh = _outer(self.H, self.H)
        fh = _outer(self.F, self.H)
        return (self.delta[e4] * ii + self.cross[e4] * (fh + np.swapaxes(np.swapaxes(fh, -4, -2), -3, -1))
                + self.hh[e4] * hh + self.hx[e4] * np.swapaxes(hh, -3, -1) + self.w11[e4] * _outer(self.D, self.D))


def _volumetric_slopes(law: Hyperelastic, J: np.ndarray, pressure_Pa: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """U'(J) and U''(J) (Pa), or the given pressure with no U'' (the caller adds the volumetric stiffness)."""
    if pressure_Pa is None:
        return volumetric(law, J)[1:]
    return pressure_Pa, np.zeros_like(J)


def i1_tangent(law: Hyperelastic, F: np.ndarray, pressure_Pa: np.ndarray | None = None) -> I1Tangent:
    """The terms of dP/dF for a law without I2bar (law.c01_Pa == 0); `pressure_Pa` as in `tangent`."""
    if law.c01_Pa:
        raise ValueError("i1_tangent takes laws in I1bar and J only; use tangent for Mooney-Rivlin")
    kin = _Kinematics(F)
    i1b, d1 = _first(kin)
    w1, w11 = _isochoric(law, i1b)
    wj, wjj = _volumetric_slopes(law, kin.J, pressure_Pa)
    J, I1 = kin.J, kin.I1
    s = w1 * J ** (-2 / 3)
    # w1 d2I1bar/dF2 = s (2 d_ik d_JL - 4/3 (F x H + H x F) + 4/9 I1 H x H + 2/3 I1 H_iL H_kJ), plus the volumetric part
    P = w1[..., None, None] * d1 + (wj * J)[..., None, None] * kin.H
    return I1Tangent(P, kin.F, kin.H, d1, 2.0 * s, -(4 / 3) * s, (4 / 9) * s * I1 + wjj * J**2 + wj * J,
                     (2 / 3) * s * I1 - wj * J, w11)


def _field(x, shape: tuple[int, ...]) -> np.ndarray:
    """A field over the points `shape` (scalar, or with trailing (3, 3)) as a contiguous float array."""
    x = np.asarray(x, dtype=float)
    tail = x.shape[len(shape):] if x.ndim > len(shape) else ()
    return np.ascontiguousarray(np.broadcast_to(x, shape + tail))


class MooneyRivlinFields(NamedTuple):
    """What gives P and A = dP/dF of a law linear in I2bar (`fea.kernels.mooney_rivlin_tangent`) at each point: F and
    H = F^-T (..., 3, 3), J, I1 = tr C, w1 = dW/dI1bar, w11 = d2W/dI1bar2, w2 = dW/dI2bar and the volumetric
    vhh = U'' J^2 + U' J, vhx = U' J (..., in Pa)."""

    F: np.ndarray
    H: np.ndarray
    J: np.ndarray
    I1: np.ndarray
    w1: np.ndarray
    w11: np.ndarray
    w2: np.ndarray
    vhh: np.ndarray
    vhx: np.ndarray

    def flat(self) -> "MooneyRivlinFields":
        """The same fields with the points in one axis, as the kernels take them."""
        points = self.J.ndim
        return MooneyRivlinFields(*(x.reshape((-1,) + x.shape[points:]) for x in self))


def mooney_rivlin_fields(law: Hyperelastic, F: np.ndarray, pressure_Pa: np.ndarray | None = None) -> MooneyRivlinFields:
    """`MooneyRivlinFields` at each F (..., 3, 3), contiguous; `pressure_Pa` as in `tangent`."""
    kin = _Kinematics(F)
    w1, w11 = _isochoric(law, kin.J ** (-2 / 3) * kin.I1)
    wj, wjj = _volumetric_slopes(law, kin.J, pressure_Pa)
    fields = (kin.F, kin.H, kin.J, kin.I1, w1, w11, law.c01_Pa, wjj * kin.J**2 + wj * kin.J, wj * kin.J)
    return MooneyRivlinFields(*(_field(x, kin.J.shape) for x in fields))


def _mooney_rivlin_stress(f: MooneyRivlinFields) -> np.ndarray:
    """P (n, 3, 3) in Pa from flat fields, one compiled pass per point (`fea.kernels.mooney_rivlin_stress`)."""
    return mooney_rivlin_stress(f.F, f.H, f.J, f.I1, f.w1, f.w2, f.vhx)


def tangent(law: Hyperelastic, F: np.ndarray, pressure_Pa: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """P (..., 3, 3) and A = dP/dF (..., 3, 3, 3, 3) with A[..., i, J, k, L] = dP_iJ / dF_kL (Pa).
    With `pressure_Pa` (U' given, as in `stress`), U'' is left out: the caller adds the volumetric stiffness.
    Laws without I2bar are built from `i1_tangent`; Mooney-Rivlin from the second derivatives of both invariants, in
    one compiled pass per point (`fea.kernels.mooney_rivlin_tangent`)."""
    if not law.c01_Pa:
        t = i1_tangent(law, F, pressure_Pa)
        return t.P, t.full()
    f = mooney_rivlin_fields(law, F, pressure_Pa).flat()
    return _mooney_rivlin_stress(f).reshape(F.shape), mooney_rivlin_tangent(*f).reshape(F.shape + (3, 3))
