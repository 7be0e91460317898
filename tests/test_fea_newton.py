"""Newton's stall rule (`fea.newton.stalled`): a solve whose residual wanders gives up, one that converges, even
only linearly at a fair rate, does not. The sequences: Newton's own on a creasing notch (the 8 x 4 mm candidate's
path mesh, the first 12 of an attempt that took 49 iterations), quadratic and linear convergence written out."""

from __future__ import annotations

from seadesign.fea.newton import NewtonSettings, stalled

# residual norms (N) of an attempt at 0.4348 rad on the 8 x 4 mm candidate's crease (measured)
CREASE = [16.0, 16.0, 11.0, 12.0, 9.4, 8.8, 12.0, 15.0, 12.0, 10.0, 9.3, 12.0]


def test_a_wandering_residual_stalls_after_the_window():
    assert not any(stalled(CREASE[:n], 10) for n in range(1, 11))  # fewer than 11 norms: not judged yet
    assert stalled(CREASE[:11], 10)  # 9.3 is more than half of 16


def test_converging_residuals_never_stall():
    quadratic = [1.0]
    while quadratic[-1] > 1e-12:
        quadratic.append(min(0.5 * quadratic[-1], quadratic[-1] ** 2))
    linear = [0.92 ** k for k in range(60)]  # 0.92^10 = 0.43: halves within the window
    for norms in (quadratic, linear):
        assert not any(stalled(norms[:n], 10) for n in range(1, len(norms) + 1))
    slow = [0.95 ** k for k in range(12)]  # 0.95^10 = 0.60: does not halve
    assert stalled(slow[:11], 10) and not stalled(slow[:10], 10)


def test_without_a_window_nothing_stalls():
    assert NewtonSettings().stall_window is None
    assert not stalled(CREASE * 10, None)
