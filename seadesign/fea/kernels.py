"""Compiled element loops of the finite-strain solid and the block assembly: deformation gradients,
internal-force contractions, the tangent's pair blocks K_ab[i, k] = sum_q w_q G_aJ A_iJkL G_bL (N/m)
from the law's tangent at the quadrature points, det F with F^-T, and the sum of element blocks into
the global ones. Shape-function gradients are G_a = sum_j D[q, a, j] Gamma_j (1/m): the constant
derivatives D of the reference element and each element's barycentric gradients Gamma.

Each loop makes one pass per element and quadrature point, where NumPy needs several passes over
(m, q, nen, 3) temporaries (docs/validation/timing.md gives the measured times). Compiled by numba (cadquery installs it),
cached on disk after the first call.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def _gradients(dlam: np.ndarray, gamma: np.ndarray, q: int, e: int, out: np.ndarray) -> None:
    """G_a = sum_j D[q, a, j] Gamma[e, j] into out (nen, 3)."""
    for a in range(dlam.shape[1]):
        for i in range(3):
            s = 0.0
            for j in range(4):
                s += dlam[q, a, j] * gamma[e, j, i]
            out[a, i] = s


@njit(cache=True, nogil=True)
def _apply(x: np.ndarray, g: np.ndarray, out: np.ndarray) -> None:
    """(X G_a)_i = X_iJ G_aJ into out (nen, 3) for X (3, 3)."""
    for a in range(g.shape[0]):
        for i in range(3):
            out[a, i] = x[i, 0] * g[a, 0] + x[i, 1] * g[a, 1] + x[i, 2] * g[a, 2]


@njit(cache=True, nogil=True)
def i1_pair_blocks(dlam: np.ndarray, gamma: np.ndarray, weights: np.ndarray, F: np.ndarray, H: np.ndarray,
                   D: np.ndarray, delta: np.ndarray, cross: np.ndarray, hh: np.ndarray, hx: np.ndarray,
                   w11: np.ndarray, ia: np.ndarray, ib: np.ndarray) -> np.ndarray:
    """Pair blocks (P, m, 3, 3) of a law in I1bar and J (`hyperelastic.I1Tangent`): with A = delta d_ik d_JL
    + cross (F_iJ H_kL + H_iJ F_kL) + hh H_iJ H_kL + hx H_iL H_kJ + w11 D_iJ D_kL,
    K_ab[i, k] = sum_q w (delta (G_a . G_b) d_ik + cross ((F G_a)_i (H G_b)_k + (H G_a)_i (F G_b)_k)
    + hh (H G_a)_i (H G_b)_k + hx (H G_b)_i (H G_a)_k + w11 (D G_a)_i (D G_b)_k).
    dlam (q, nen, 4), gamma (m, 4, 3), weights (m, q) in m^3, F, H, D (m, q, 3, 3), the terms (m, q) in Pa."""
    m, nq, nen, npairs = gamma.shape[0], dlam.shape[0], dlam.shape[1], len(ia)
    out = np.zeros((npairs, m, 3, 3))
    g, fg, hg, dg = np.empty((nen, 3)), np.empty((nen, 3)), np.empty((nen, 3)), np.empty((nen, 3))
    for e in range(m):
        for q in range(nq):
            w = weights[e, q]
            _gradients(dlam, gamma, q, e, g)
            _apply(F[e, q], g, fg)
            _apply(H[e, q], g, hg)
            use_d = w11[e, q] != 0.0
            if use_d:
                _apply(D[e, q], g, dg)
            cd, cc, ch, cx, c11 = w * delta[e, q], w * cross[e, q], w * hh[e, q], w * hx[e, q], w * w11[e, q]
            for p in range(npairs):
                a, b = ia[p], ib[p]
                gg = cd * (g[a, 0] * g[b, 0] + g[a, 1] * g[b, 1] + g[a, 2] * g[b, 2])
                for i in range(3):
                    for k in range(3):
                        v = (cc * (fg[a, i] * hg[b, k] + hg[a, i] * fg[b, k]) + ch * hg[a, i] * hg[b, k]
                             + cx * hg[b, i] * hg[a, k])
                        if use_d:
                            v += c11 * dg[a, i] * dg[b, k]
                        if i == k:
                            v += gg
                        out[p, e, i, k] += v
    return out


@njit(cache=True, nogil=True)
def mooney_rivlin_pair_blocks(dlam: np.ndarray, gamma: np.ndarray, weights: np.ndarray, F: np.ndarray, H: np.ndarray,
                              J: np.ndarray, I1: np.ndarray, w1: np.ndarray, w11: np.ndarray, w2: np.ndarray,
                              vhh: np.ndarray, vhx: np.ndarray, ia: np.ndarray, ib: np.ndarray) -> np.ndarray:
    """Pair blocks (P, m, 3, 3) of a law linear in I2bar: K_ab[i, k] = sum_q w sum_JL G_aJ A_iJkL G_bL with A at each
    point as in `mooney_rivlin_tangent` (its fields (m, q), F and H (m, q, 3, 3)), built and contracted in one pass."""
    m, nq, nen, npairs = gamma.shape[0], dlam.shape[0], dlam.shape[1], len(ia)
    out = np.zeros((npairs, m, 3, 3))
    g = np.empty((nen, 3))
    a4 = np.empty((3, 3, 3, 3))
    t = np.empty((nen, 3, 3, 3))  # T_a[i, k, L] = w sum_J G_aJ A_iJkL
    work = np.empty((6, 3, 3))
    for e in range(m):
        for q in range(nq):
            w = weights[e, q]
            _gradients(dlam, gamma, q, e, g)
            _mooney_rivlin_point(F[e, q], H[e, q], J[e, q], I1[e, q], w1[e, q], w11[e, q], w2[e, q], vhh[e, q],
                                 vhx[e, q], work, a4)
            for a in range(nen):
                for i in range(3):
                    for k in range(3):
                        for L in range(3):
                            t[a, i, k, L] = w * (g[a, 0] * a4[i, 0, k, L] + g[a, 1] * a4[i, 1, k, L]
                                                 + g[a, 2] * a4[i, 2, k, L])
            for p in range(npairs):
                a, b = ia[p], ib[p]
                for i in range(3):
                    for k in range(3):
                        out[p, e, i, k] += t[a, i, k, 0] * g[b, 0] + t[a, i, k, 1] * g[b, 1] + t[a, i, k, 2] * g[b, 2]
    return out


@njit(cache=True, nogil=True)
def _cauchy_green(f: np.ndarray, i1: float, c: np.ndarray) -> float:
    """C = F^T F of f (3, 3) into c (3, 3); returns I2 = (I1^2 - C:C) / 2 (i1 = tr C)."""
    cc = 0.0
    for r in range(3):
        for s in range(3):
            c[r, s] = f[0, r] * f[0, s] + f[1, r] * f[1, s] + f[2, r] * f[2, s]
            cc += c[r, s] * c[r, s]
    return 0.5 * (i1 * i1 - cc)


@njit(cache=True, nogil=True)
def mooney_rivlin_stress(F: np.ndarray, H: np.ndarray, J: np.ndarray, I1: np.ndarray, w1: np.ndarray, w2: np.ndarray,
                         vh: np.ndarray) -> np.ndarray:
    """P = dW/dF (n, 3, 3) in Pa of W(I1bar, I2bar, J) linear in I2bar at each F (n, 3, 3) (H = F^-T, J, I1 = tr C):
    w1 dI1bar/dF + w2 dI2bar/dF + vh H, with w1 = dW/dI1bar, w2 = dW/dI2bar and vh = U' J (Pa);
    dI1bar/dF = J^-2/3 (2 F - 2/3 I1 H), dI2bar/dF = J^-4/3 (2 (I1 F - F C) - 4/3 I2 H)."""
    n = F.shape[0]
    out = np.empty((n, 3, 3))
    c = np.empty((3, 3))
    for e in range(n):
        f, h = F[e], H[e]
        j23, j43 = J[e] ** (-2.0 / 3.0), J[e] ** (-4.0 / 3.0)
        i1 = I1[e]
        i2 = _cauchy_green(f, i1, c)
        for r in range(3):
            for s in range(3):
                fc = f[r, 0] * c[0, s] + f[r, 1] * c[1, s] + f[r, 2] * c[2, s]
                d1 = j23 * (2.0 * f[r, s] - (2.0 / 3.0) * i1 * h[r, s])
                d2 = j43 * (2.0 * (i1 * f[r, s] - fc) - (4.0 / 3.0) * i2 * h[r, s])
                out[e, r, s] = w1[e] * d1 + w2[e] * d2 + vh[e] * h[r, s]
    return out


@njit(cache=True, nogil=True)
def mooney_rivlin_tangent(F: np.ndarray, H: np.ndarray, J: np.ndarray, I1: np.ndarray, w1: np.ndarray,
                          w11: np.ndarray, w2: np.ndarray, vhh: np.ndarray, vhx: np.ndarray) -> np.ndarray:
    """A = dP/dF (n, 3, 3, 3, 3), A[iJkL] = dP_iJ / dF_kL (Pa), of W(I1bar, I2bar, J) linear in I2bar at each F (n, 3, 3)
    (H = F^-T, J, I1 = tr C; I2 = I2(C)): w11 dI1b x dI1b + w1 d2I1b + w2 d2I2b + vhh H_iJ H_kL - vhx H_iL H_kJ, with
    w1 = dW/dI1bar, w11 = d2W/dI1bar2, w2 = dW/dI2bar (Pa) and the volumetric vhh = U'' J^2 + U' J, vhx = U' J (Pa);
    d2I1b = J^-2/3 (-2/3 (2 F - 2/3 I1 H) x H + 2 d_ik d_JL - 4/3 H x F + 2/3 I1 H_iL H_kJ),
    d2I2b = J^-4/3 (-4/3 (dI2 - 4/3 I2 H) x H + d2I2 - 4/3 H x dI2 + 4/3 I2 H_iL H_kJ),
    d2I2 = 2 (2 F_iJ F_kL + I1 d_ik d_JL - d_ik C_LJ - F_iL F_kJ - b_ik d_JL), dI2 = 2 (I1 F - F C), b = F F^T."""
    n = F.shape[0]
    out = np.empty((n, 3, 3, 3, 3))
    work = np.empty((6, 3, 3))
    for e in range(n):
        _mooney_rivlin_point(F[e], H[e], J[e], I1[e], w1[e], w11[e], w2[e], vhh[e], vhx[e], work, out[e])
    return out


@njit(cache=True, nogil=True)
def _mooney_rivlin_point(f: np.ndarray, h: np.ndarray, j: float, i1: float, w1: float, w11: float, w2: float,
                         vhh: float, vhx: float, work: np.ndarray, out: np.ndarray) -> None:
    """A (3, 3, 3, 3) of `mooney_rivlin_tangent` at one point into out; work (6, 3, 3) is scratch."""
    c, b, di2, x, y, d1 = work[0], work[1], work[2], work[3], work[4], work[5]
    j23, j43 = j ** (-2.0 / 3.0), j ** (-4.0 / 3.0)
    i2 = _cauchy_green(f, i1, c)
    for r in range(3):
        for s in range(3):
            b[r, s] = f[r, 0] * f[s, 0] + f[r, 1] * f[s, 1] + f[r, 2] * f[s, 2]
    for r in range(3):
        for s in range(3):
            fc = f[r, 0] * c[0, s] + f[r, 1] * c[1, s] + f[r, 2] * c[2, s]
            di2[r, s] = 2.0 * (i1 * f[r, s] - fc)
            x[r, s] = 2.0 * f[r, s] - (2.0 / 3.0) * i1 * h[r, s]
            y[r, s] = di2[r, s] - (4.0 / 3.0) * i2 * h[r, s]
            d1[r, s] = j23 * x[r, s]
    for i in range(3):
        for jj in range(3):
            for k in range(3):
                for L in range(3):
                    dik, djl = 1.0 if i == k else 0.0, 1.0 if jj == L else 0.0
                    hx = h[i, L] * h[k, jj]
                    dd1 = j23 * (-(2.0 / 3.0) * x[i, jj] * h[k, L] + 2.0 * dik * djl - (4.0 / 3.0) * h[i, jj] * f[k, L]
                                 + (2.0 / 3.0) * i1 * hx)
                    ddi2 = 2.0 * (2.0 * f[i, jj] * f[k, L] + i1 * dik * djl - dik * c[L, jj] - f[i, L] * f[k, jj]
                                  - b[i, k] * djl)
                    dd2 = j43 * (-(4.0 / 3.0) * y[i, jj] * h[k, L] + ddi2 - (4.0 / 3.0) * h[i, jj] * di2[k, L]
                                 + (4.0 / 3.0) * i2 * hx)
                    out[i, jj, k, L] = (w11 * d1[i, jj] * d1[k, L] + w1 * dd1 + w2 * dd2 + vhh * h[i, jj] * h[k, L]
                                        - vhx * hx)


@njit(cache=True, nogil=True)
def deformation_gradients(dlam: np.ndarray, gamma: np.ndarray, elements: np.ndarray, u: np.ndarray) -> np.ndarray:
    """F = I + sum_a u_a G_a^T (m, q, 3, 3) at the quadrature points; elements (m, nen), u (N, 3) in m."""
    m, nq, nen = gamma.shape[0], dlam.shape[0], dlam.shape[1]
    out = np.zeros((m, nq, 3, 3))
    g = np.empty((nen, 3))
    for e in range(m):
        for q in range(nq):
            _gradients(dlam, gamma, q, e, g)
            for a in range(nen):
                node = elements[e, a]
                for i in range(3):
                    ui = u[node, i]
                    for j in range(3):
                        out[e, q, i, j] += ui * g[a, j]
            for i in range(3):
                out[e, q, i, i] += 1.0
    return out


@njit(cache=True, nogil=True)
def contract(dlam: np.ndarray, gamma: np.ndarray, weights: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Element vectors f_ai = sum_q w P_iJ G_aJ (m, nen, 3) of a stress-like field P (m, q, 3, 3) in Pa."""
    m, nq, nen = gamma.shape[0], dlam.shape[0], dlam.shape[1]
    out = np.zeros((m, nen, 3))
    g = np.empty((nen, 3))
    for e in range(m):
        for q in range(nq):
            w = weights[e, q]
            _gradients(dlam, gamma, q, e, g)
            for a in range(nen):
                for i in range(3):
                    out[e, a, i] += w * (P[e, q, i, 0] * g[a, 0] + P[e, q, i, 1] * g[a, 1] + P[e, q, i, 2] * g[a, 2])
    return out


@njit(cache=True, nogil=True)
def add_element_vectors(f: np.ndarray, elements: np.ndarray, fe: np.ndarray) -> None:
    """f[elements[e, a]] += fe[e, a] (in place) for nodal vectors f (N, 3) and element vectors fe (m, nen, 3)."""
    for e in range(elements.shape[0]):
        for a in range(elements.shape[1]):
            node = elements[e, a]
            for i in range(3):
                f[node, i] += fe[e, a, i]


@njit(cache=True, nogil=True)
def det_inverse_transpose(F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """det F (n,) and F^-T (n, 3, 3) of F (n, 3, 3) from the cofactors; det F <= 0 is left to the caller."""
    n = F.shape[0]
    J, H = np.empty(n), np.empty((n, 3, 3))
    for e in range(n):
        f = F[e]
        for j in range(3):  # column j of the cofactor matrix is c_(j+1) x c_(j+2), c_j the columns of F
            a, b = (j + 1) % 3, (j + 2) % 3
            for i in range(3):
                k, m = (i + 1) % 3, (i + 2) % 3
                H[e, i, j] = f[k, a] * f[m, b] - f[m, a] * f[k, b]
        J[e] = f[0, 0] * H[e, 0, 0] + f[1, 0] * H[e, 1, 0] + f[2, 0] * H[e, 2, 0]
        for i in range(3):
            for j in range(3):
                H[e, i, j] /= J[e]
    return J, H


@njit(cache=True, nogil=True)
def sum_blocks(blocks: np.ndarray, target: np.ndarray, flip: np.ndarray, n: int) -> np.ndarray:
    """Global blocks (n, d, d): the sum of blocks (k, d, d) over their targets (-1: dropped), each transposed
    where `flip`."""
    d = blocks.shape[1]
    out = np.zeros((n, d, d))
    for b in range(blocks.shape[0]):
        t = target[b]
        if t < 0:
            continue
        if flip[b]:
            for i in range(d):
                for j in range(d):
                    out[t, i, j] += blocks[b, j, i]
        else:
            for i in range(d):
                for j in range(d):
                    out[t, i, j] += blocks[b, i, j]
    return out
