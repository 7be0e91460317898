"""Deliberately simple data generators, written apart from `seadesign.twin` and `seadesign.effects`: a few
lines of explicit physics each, integrated in their own way (analytic drive, explicit Euler substeps for
the stateful effects), so an error in a library effect's forward model cannot cancel itself in a test.

Effect parameters use the library's names and units (the loop reports them so; nothing is translated).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

K = 9.106  # the thesis's measured spring (Nm/rad)


def _euler_lag(x: np.ndarray, dt: float, tau: float, sub: int = 20) -> np.ndarray:
    """y' = (x - y) / tau by explicit Euler with `sub` substeps per sample (x held), y(0) = x(0)."""
    y, out, h = x[0], np.empty_like(x), dt / sub
    for i, xi in enumerate(x):
        for _ in range(sub if i else 0):
            y += h * (xi - y) / tau
        out[i] = y
    return out


def _dahl(d: np.ndarray, torque: float, stiffness: float) -> np.ndarray:
    """dz/dd = sigma (1 - z sign(dd) / tau_h) by explicit Euler, each sample's deflection step cut into substeps
    of at most a fiftieth of tau_h / sigma (at least 50)."""
    z, out = 0.0, np.empty_like(d)
    for i in range(d.size):
        step = d[i] - d[i - 1] if i else 0.0
        sub = max(50, int(np.ceil(50 * stiffness * abs(step) / torque)))
        dd = step / sub
        for _ in range(sub if i else 0):
            z += stiffness * (1 - z * np.sign(dd) / torque) * dd
        out[i] = z
    return out


def _dahl_from_torque(tau: np.ndarray, k: float, torque: float, stiffness: float) -> np.ndarray:
    """Deflection d of a spring k d + z = tau with a Dahl loop z (dz/dd = sigma (1 - z sign(dd) / tau_h)) driven
    by the torque: dd = dtau / (k + sigma (1 - z s / tau_h)), s = sign(dtau), by explicit Euler, each sample's
    torque step cut into substeps of at most a fiftieth of tau_h min(1, k / sigma) (at least 50; the bound keeps
    the near-saturated stretch, rate sigma / (k tau_h), stable); z(0) = 0."""
    z, d, out = 0.0, tau[0] / k, np.empty_like(tau)
    out[0] = d
    for i in range(1, tau.size):
        step = tau[i] - tau[i - 1]
        sub = max(50, int(np.ceil(50 * abs(step) / torque * max(1.0, stiffness / k))))
        h = step / sub
        for _ in range(sub):
            slope = stiffness * (1 - z * np.sign(h) / torque)
            dd = h / (k + slope)
            z += slope * dd
            d += dd
        out[i] = d
    return out


def _maxwell_from_torque(tau: np.ndarray, dt: float, k: float, k2: float, tr: float, sub: int = 20) -> np.ndarray:
    """Deflection d of a spring k with a Maxwell arm (k2, relaxation time tr) in parallel carrying tau:
    tau = k d + k2 (d - r), r' = (d - r) / tr, by explicit Euler in r with `sub` substeps per sample (tau held);
    relaxed at the start, r(0) = d(0) = tau(0) / k."""
    r, out, h = tau[0] / k, np.empty_like(tau), dt / sub
    for i, ti in enumerate(tau):
        for _ in range(sub if i else 0):
            r += h * ((ti + k2 * r) / (k + k2) - r) / tr
        out[i] = (ti + k2 * r) / (k + k2)
    return out


def bench(effects: dict[str, dict[str, float]], seed: int = 1, duration_s: float = 60.0, rate_hz: float = 100.0,
          frequency_hz: float = 0.1, torque_amplitude_Nm: float = 4.8, k: float = K, harmonic: bool = True) -> pd.DataFrame:
    """A torque-deflection bench test: the deflection driven by two sines (`frequency_hz` and 3.7 times it, 70 / 30 %
    of the amplitude; one sine without `harmonic`), so that a phase lead that grows with frequency
    (viscoelasticity) differs from a delay;
    the torque sensor reads the spring torque (+ bench friction); the deflection reading carries the sensor
    effects. Bench format columns."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(duration_s * rate_hz)) / rate_hz
    w, a = 2 * np.pi * frequency_hz, torque_amplitude_Nm / k
    e = effects

    h = 0.3 if harmonic else 0.0

    def drive(time):
        return a * ((1 - h) * np.sin(w * time) + h * np.sin(3.7 * w * time + 1.0))

    d, rate = drive(t), a * w * ((1 - h) * np.cos(w * t) + 3.7 * h * np.cos(3.7 * w * t + 1.0))
    b = e.get("dead_band", {}).get("width_rad", 0.0)
    ds = np.sign(d) * np.maximum(np.abs(d) - b / 2, 0.0)
    tau = k * e.get("stiffness_scale", {}).get("scale", 1.0) * ds + e.get("cubic_stiffening", {}).get("k3_Nm_per_rad3", 0.0) * ds ** 3
    if "hysteresis" in e:
        tau = tau + _dahl(ds, e["hysteresis"]["torque_Nm"], e["hysteresis"]["stiffness_Nm_per_rad"])
    if "viscoelastic" in e:
        p = e["viscoelastic"]
        tau = tau + p["maxwell_stiffness_Nm_per_rad"] * (ds - _euler_lag(ds, t[1], p["relaxation_time_s"]))
    if "thermal_softening" in e:
        p, heat, f = e["thermal_softening"], 0.0, np.ones(t.size)
        rate_s = np.gradient(ds, t)
        for i in range(t.size):  # H' = f |tau_0 d'| - H / tc (the softened torque's power), explicit Euler
            f[i] = 1 - p["softening_per_J"] * heat
            heat += t[1] * (f[i] * abs(tau[i] * rate_s[i]) - heat / p["cooling_time_s"])
        tau = tau * f
    out = {"time_s": t}
    if "temperature_softening" in e:
        temp = 25.0 + 20.0 * np.sin(np.pi * t / t[-1])  # heated and cooled from outside: not the spring's own work
        tau = tau * (1 - e["temperature_softening"]["softening_per_K"] * (temp - temp[0]))
        out["temperature_C"] = temp
    if "friction" in e:
        p = e["friction"]
        tau = tau + p["coulomb_Nm"] * np.tanh(rate / p.get("smoothing_rad_per_s", 0.01)) + p["viscous_Nm_s_per_rad"] * rate
    reading = drive(t - e.get("sensor_delay", {}).get("delay_s", 0.0))  # the delayed reading, exactly
    reading = reading + e.get("sensor_offset", {}).get("offset_rad", 0.0) + e.get("sensor_drift", {}).get("rate_rad_per_s", 0.0) * t
    if "sensor_step" in e:
        reading = reading + e["sensor_step"]["size_rad"] * (t >= e["sensor_step"]["time_s"])
    out["torque_Nm"] = tau + rng.normal(0, 0.02, t.size)
    out["deflection_rad"] = reading + rng.normal(0, 0.001, t.size)
    return pd.DataFrame(out)


def link_motion(t: np.ndarray, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Knee angle (rad) of a leg stepping in place, hanging: two harmonics of a 0.8 s cycle, amplitude slowly
    modulated, random phases; and its first and second time derivatives (analytic)."""
    rng = np.random.default_rng(seed)
    w, m = 2 * np.pi / 0.8, 2 * np.pi / rng.uniform(6.0, 9.0)
    p1, p2, pm = rng.uniform(0, 2 * np.pi, 3)
    amp = 1 + 0.3 * np.sin(m * t + pm)
    damp, ddamp = 0.3 * m * np.cos(m * t + pm), -0.3 * m * m * np.sin(m * t + pm)
    s = 0.3 * np.sin(w * t + p1) + 0.15 * np.sin(2 * w * t + p2)
    ds = 0.3 * w * np.cos(w * t + p1) + 0.3 * w * np.cos(2 * w * t + p2)
    dds = -0.3 * w * w * np.sin(w * t + p1) - 0.6 * w * w * np.sin(2 * w * t + p2)
    return 1.2 + amp * s, damp * s + amp * ds, ddamp * s + 2 * damp * ds + amp * dds


def robot(effects: dict[str, dict[str, float]], seed: int = 1, duration_s: float = 60.0, rate_hz: float = 100.0,
          k: float = K) -> pd.DataFrame:
    """One knee (left) of a hanging robot stepping in place, robot-format columns (`time_s`, `l_knee_pos`,
    `l_hall_pos`, `l_knee_vel`, `l_hall_vel`, `l_knee_eff`).

    The link follows `link_motion`; the spring carries what the link needs: inertia (0.0158 kg m^2), gravity
    (0.96 Nm sin(q - 0.9), the leg hanging at 0.9 rad) and link damping 0.05 Nm s/rad, so the torque reverses
    twice a cycle. The spring's deflection is solved from that torque: k (scaled), with thermal softening, a Dahl
    loop, a Maxwell arm or a cubic term (one of these at a time). Motor = link + spring deflection (+ half the
    backlash towards the torque). Effort = spring torque + gear friction (motor side), lagged by the servo's filter.
    Hall = link angle through the sensor effects; noise 0.002 rad (Hall), 0.05 Nm (effort), 12-bit quantisation of
    both angles.
    """
    rng = np.random.default_rng(seed + 1000)
    e = effects
    t = np.arange(int(duration_s * rate_hz)) / rate_hz
    q, dq, ddq = link_motion(t, seed)
    tau = 0.0158 * ddq + 0.96 * np.sin(q - 0.9) + 0.05 * dq
    k_true = k * e.get("stiffness_scale", {}).get("scale", 1.0)
    if "thermal_softening" in e:
        p, heat, h = e["thermal_softening"], 0.0, np.empty(t.size)
        d_prev = 0.0
        for i in range(t.size):  # H' = |tau dd_s/dt| - H / tc with the softened spring's deflection d_s
            d_now = tau[i] / (k_true * (1 - p["softening_per_J"] * heat))
            heat += abs(tau[i] * (d_now - d_prev)) - t[1] * heat / p["cooling_time_s"] if i else 0.0
            d_prev = d_now
            h[i] = heat
        spring_defl = tau / (k_true * (1 - p["softening_per_J"] * h))
    else:
        spring_defl = tau / k_true
    if "hysteresis" in e:
        p = e["hysteresis"]
        spring_defl = _dahl_from_torque(tau, k_true, p["torque_Nm"], p["stiffness_Nm_per_rad"])
    if "viscoelastic" in e:
        p = e["viscoelastic"]
        spring_defl = _maxwell_from_torque(tau, t[1], k_true, p["maxwell_stiffness_Nm_per_rad"], p["relaxation_time_s"])
    if "cubic_stiffening" in e:  # k d + k3 d^3 = tau, by Newton from the linear deflection
        k3 = e["cubic_stiffening"]["k3_Nm_per_rad3"]
        for _ in range(30):
            spring_defl = spring_defl - (k_true * spring_defl + k3 * spring_defl ** 3 - tau) / (k_true + 3 * k3 * spring_defl ** 2)
    b = e.get("dead_band", {}).get("width_rad", 0.0)
    motor = q + spring_defl + np.sign(tau) * b / 2
    vm = np.gradient(motor, t)
    effort = tau.copy()
    if "friction" in e:
        p = e["friction"]
        effort = effort + p["coulomb_Nm"] * np.tanh(vm / p.get("smoothing_rad_per_s", 0.05)) + p.get("viscous_Nm_s_per_rad", 0.0) * vm
    if "effort_lag" in e:
        effort = _euler_lag(effort, t[1], e["effort_lag"]["time_constant_s"])
    hall = link_motion(t - e.get("sensor_delay", {}).get("delay_s", 0.0), seed)[0]  # the delayed reading, exactly
    hall = hall + e.get("sensor_offset", {}).get("offset_rad", 0.0) + e.get("sensor_drift", {}).get("rate_rad_per_s", 0.0) * t
    if "sensor_step" in e:
        hall = hall + e["sensor_step"]["size_rad"] * (t >= e["sensor_step"]["time_s"])
    q12 = 2 * np.pi / 4096
    hall = np.round((hall + rng.normal(0, 0.002, t.size)) / q12) * q12
    motor_read = np.round(motor / q12) * q12
    return pd.DataFrame({"time_s": t, "l_knee_pos": motor_read, "l_hall_pos": hall, "l_knee_vel": vm,
                         "l_hall_vel": np.gradient(hall, t), "l_knee_eff": effort + rng.normal(0, 0.05, t.size)})


def bench_curve(torque_of_rotation, scale: float, amplitude_rad: float, seed: int = 1, duration_s: float = 60.0,
                rate_hz: float = 100.0, frequency_hz: float = 0.1, torque_delay_s: float = 0.0,
                torque_time_constant_s: float = 0.0) -> pd.DataFrame:
    """A bench test of a nonlinear spring: the deflection driven by two sines (`frequency_hz` and 3.7 times it,
    70 / 30 % of `amplitude_rad`), the torque `scale` x `torque_of_rotation(d)` (Nm, a closed-form function odd
    in d). The torque channel may lag the deflection: a pure delay (`torque_delay_s`, evaluated exactly) or a
    first-order low-pass (`torque_time_constant_s`, explicit Euler in 20 substeps). Noise 0.02 Nm on the torque,
    0.001 rad on the deflection. Bench format columns."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(duration_s * rate_hz)) / rate_hz
    w = 2 * np.pi * frequency_hz

    def drive(time):
        return amplitude_rad * (0.7 * np.sin(w * time) + 0.3 * np.sin(3.7 * w * time + 1.0))

    torque = scale * torque_of_rotation(drive(t - torque_delay_s))
    if torque_time_constant_s > 0:
        torque = _euler_lag(torque, t[1], torque_time_constant_s)
    return pd.DataFrame({"time_s": t, "torque_Nm": torque + rng.normal(0, 0.02, t.size),
                         "deflection_rad": drive(t) + rng.normal(0, 0.001, t.size)})
