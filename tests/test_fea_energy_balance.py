"""The path's energy balance through contact (`path_events.energy_balanced`) on curves whose work is known in
closed form: the hub's work over an increment equals the energy's increase for a cubic curve (Hermite's rule is
exact), for a curve whose tangent jumps (contact onset) within the allowance at any step, and an energy loss is
caught once it passes the contact's allowed work."""

from __future__ import annotations

import math

import pytest

from seadesign.fea.path_events import energy_balanced
from seadesign.fea.torque_path import PathPoint


def _point(theta: float, torque: float, tangent: float) -> PathPoint:
    return PathPoint(theta, torque, tangent, 0.0, math.inf, 1, (0.0,))


def test_a_cubic_curve_balances_to_round_off():
    a, b = 30.0, -40.0  # T = a t + b t^3 (Nm), U = a t^2 / 2 + b t^4 / 4 (J)
    torque, tangent = (lambda t: a * t + b * t**3), (lambda t: a + 3 * b * t**2)
    energy = lambda t: a * t**2 / 2 + b * t**4 / 4
    p0, p1 = _point(0.3, torque(0.3), tangent(0.3)), _point(0.3001, torque(0.3001), tangent(0.3001))
    assert energy_balanced(p0, p1, energy(0.3), energy(0.3001), 0.0)
    for t0, t1 in ((0.0, 0.3), (0.2, 0.21), (0.1, 0.5)):
        p0, p1 = _point(t0, torque(t0), tangent(t0)), _point(t1, torque(t1), tangent(t1))
        assert energy_balanced(p0, p1, energy(t0), energy(t1), 0.0)
        # the allowance for the curve's shape is 4 |kink| about the exact work, kink = h^2 / 12 (T'a - T'b)
        kink = (t1 - t0) ** 2 / 12 * (tangent(t0) - tangent(t1))
        assert energy_balanced(p0, p1, energy(t0), energy(t1) + 3.5 * kink, 0.0)
        assert not energy_balanced(p0, p1, energy(t0), energy(t1) - 4.5 * kink, 0.0)
    # a jump that loses 1 mJ loses it at every step; the allowance for the curve's shape shrinks as the step squared
    caught = []
    for h in (0.2, 0.1, 0.05, 0.02, 0.01):
        p0, p1 = _point(0.3, torque(0.3), tangent(0.3)), _point(0.3 + h, torque(0.3 + h), tangent(0.3 + h))
        caught.append(not energy_balanced(p0, p1, energy(0.3), energy(0.3 + h) - 1e-3, 0.0))
    assert caught == [False, False, False, True, True]  # the allowance: 0.26, 0.028, 0.0033, 2e-4, 2.4e-5 J


@pytest.mark.parametrize("fraction", [0.0, 0.1, 0.5, 0.9])
@pytest.mark.parametrize("h", [0.1, 0.01, 0.001])
def test_a_tangent_jump_passes_at_every_step_and_fraction(h, fraction):
    # T = k1 t, then stiffer (k2) past the kink at t_c: the surfaces touch inside the increment
    k1, k2, t_c = 20.0, 80.0, 0.3
    t0 = t_c - fraction * h
    t1 = t0 + h
    torque = lambda t: k1 * t if t <= t_c else k1 * t_c + k2 * (t - t_c)
    energy = lambda t: k1 * t**2 / 2 if t <= t_c else k1 * t_c**2 / 2 + k1 * t_c * (t - t_c) + k2 * (t - t_c) ** 2 / 2
    p0, p1 = _point(t0, torque(t0), k1 if t0 < t_c else k2), _point(t1, torque(t1), k2)
    assert energy_balanced(p0, p1, energy(t0), energy(t1), 0.0)


def test_energy_lost_passes_only_within_the_contact_work_allowed():
    p0, p1 = _point(0.30, 9.0, 30.0), _point(0.31, 9.3, 30.0)  # a straight curve: the work is the trapezoid
    work = 0.01 * (9.0 + 9.3) / 2
    lost = 1e-5  # J
    assert not energy_balanced(p0, p1, 1.0, 1.0 + work - lost, 0.5 * lost)
    assert energy_balanced(p0, p1, 1.0, 1.0 + work - lost, 2 * lost)
