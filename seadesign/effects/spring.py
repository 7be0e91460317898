"""Effects in the torque path of the spring: deflection -> torque.

Order in a chain: dead zones act on `deflection` first, then the spring (`LinearSpring` or the
large-deflection `SpringCurve`, see `curve.py`) turns it into `torque`, then the torque effects add
or scale. Each effect's whole-array model is vectorised (`apply`); a fitter that predicts the
deflection from a torque (the compliance direction) uses the inverse pieces defined here:
`solve_cubic`, `dahl_in_series`, `sls_deflection`, `softening_marched`, `DeadBand.free_travel`.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.signal import lfilter, lfilter_zi
from scipy.special import erf, wrightomega

from seadesign.constants import THESIS_K_MEASURED_NM_PER_RAD
from seadesign.effects.base import EXACT, Effect, Param, Scales, Search, lowpass, rows, time_steps


class DeadBand(Effect):
    """Dead zone of total width b in the deflection: no torque while |deflection| < b/2.

    Used for the spring's own dead-band (fig. 5.5) and, as a second instance named
    `backlash`, for the gearbox backlash between motor and spring.
    """

    key = "dead_band"
    summary = "dead zone of total width b: deflection -> sign(d) max(|d| - b/2, 0)"
    signature = "flat/S-shape near zero deflection; a step of b at each torque reversal"
    parameters = (Param("width_rad", "rad", 0.01, 0.0, 0.5, "total width b of the dead zone"),)
    reads = ("deflection",)
    writes = "deflection"

    def _map(self, x, p, rng, xp=np, options=EXACT):
        d, half, s = x["deflection"], 0.5 * p["width_rad"], options.dead_zone_smoothing_rad
        if s is None:
            return xp.sign(d) * xp.maximum(xp.abs(d) - half, 0.0)
        softplus = options.softplus or (lambda z: xp.logaddexp(xp.zeros_like(z), z))
        return s * (softplus((d - half) / s) - softplus((-d - half) / s))

    @staticmethod
    def free_travel(spring_deflection: np.ndarray, width_rad: float, noise_rad: float = 0.0) -> np.ndarray:
        """Deflection (rad) across the zone when the spring carries `spring_deflection`: the inverse,
        d + sign(d) b/2, for a deflection known from the torque. Known only to `noise_rad` (1 sigma), the side
        is uncertain near zero and the expected travel is d + erf(d / (sqrt(2) noise)) b/2."""
        side = np.sign(spring_deflection)
        if noise_rad > 0:  # erf only where it differs from the sign (within 6 sigma of zero)
            near = np.abs(spring_deflection) < 6.0 * noise_rad
            side[near] = erf(spring_deflection[near] / (math.sqrt(2) * noise_rad))
        return spring_deflection + side * 0.5 * width_rad

    def search(self, s: Scales) -> Search:
        hi = min(0.5, 2.0 * s.deflection_rad)
        return {"width_rad": (0.0, hi)}, [{"width_rad": f * s.deflection_rad} for f in (0.05, 0.2)]


class LinearSpring(Effect):
    """The SEA spring: torque += k * deflection."""

    key = "spring"
    summary = "linear torsion spring: torque += k d"
    parameters = (Param("k_Nm_per_rad", "Nm/rad", THESIS_K_MEASURED_NM_PER_RAD, 1e-3, 1e6, "torsional stiffness k"),)
    reads = ("deflection",)
    writes = "torque"

    def _map(self, x, p, rng, xp=np, options=EXACT):
        return x["torque"] + p["k_Nm_per_rad"] * x["deflection"]


class StiffnessScale(Effect):
    """Stiffness off by a factor (wrong modulus or infill): torque *= s."""

    key = "stiffness_scale"
    summary = "torque *= s (effective modulus or infill differs from the model)"
    signature = "residual proportional to the spring torque"
    parameters = (Param("scale", "1", 1.0, 0.01, 100.0, "ratio of true to modelled stiffness"),)
    writes = "torque"
    log_params = ("scale",)
    batch_params = ("scale",)

    def _map(self, x, p, rng, xp=np, options=EXACT):
        return p["scale"] * x["torque"]

    def search(self, s: Scales) -> Search:
        return {"scale": (0.01, 100.0)}, [{"scale": v} for v in (1.0, 0.1, 10.0)]


def solve_cubic(x: np.ndarray, r: float, iterations: int = 12) -> np.ndarray:
    """d with d + r d^3 = x elementwise (Newton from d = x); for r < 0 d stays within the turning
    points +-1/sqrt(-3 r), beyond which no deflection carries the torque."""
    d = np.array(x, dtype=float)
    turn = 1.0 / math.sqrt(-3.0 * r) if r < 0 else math.inf
    tol = 1e-13 * (float(np.max(np.abs(d))) if d.size else 0.0)
    for _ in range(iterations):
        d2 = d * d
        f = d * (1.0 + r * d2) - x
        if not np.max(np.abs(f), initial=0.0) > tol:  # converged (a turning point's clip leaves a residual)
            break
        d = d - f / np.maximum(1.0 + 3.0 * r * d2, 1e-3)
        if r < 0:
            d = np.clip(d, -turn, turn)
    return d


class CubicStiffening(Effect):
    """Odd cubic term: torque += k3 d^3 (k3 > 0 stiffening, k3 < 0 softening)."""

    key = "cubic_stiffening"
    summary = "torque += k3 d^3"
    signature = "odd cubic residual vs deflection"
    parameters = (Param("k3_Nm_per_rad3", "Nm/rad^3", 2.0, -1e4, 1e4, "cubic stiffness coefficient"),)
    reads = ("deflection",)
    writes = "torque"

    def _map(self, x, p, rng, xp=np, options=EXACT):
        return x["torque"] + p["k3_Nm_per_rad3"] * x["deflection"] ** 3

    def search(self, s: Scales) -> Search:
        bound = 10.0 * s.k_Nm_per_rad / s.deflection_rad ** 2  # k3 d^3 up to 10 k d at the largest deflection
        return {"k3_Nm_per_rad3": (-bound, bound)}, [{"k3_Nm_per_rad3": 0.0}]


def dahl(d: np.ndarray, torque: float, stiffness: float, block: int = 16) -> np.ndarray:
    """Dahl hysteresis torque z (unit of `torque`) along a 1-D deflection record, vectorised.

    The recursion of `DahlHysteresis.step` (z_n = a_n z_{n-1} + (1 - a_n) s_n tau_h,
    a_n = exp(-sigma |dd_n| / tau_h)), solved in closed form within blocks of `block` samples
    (all blocks at once) and carried from block to block. Each sample's decay exponent is capped
    at 40 (a_n < 5e-18 either way), so a block's exponents stay below 640 and finite.
    """
    n = d.size
    step = np.diff(d, prepend=d[0])
    decay = np.abs(step) * (stiffness / torque)
    b = np.sign(step) * torque * -np.expm1(-decay)
    pad = -n % block
    v = np.cumsum(np.pad(np.minimum(decay, 40.0), (0, pad)).reshape(-1, block), axis=1)
    local = np.exp(-v) * np.cumsum(np.pad(b, (0, pad)).reshape(-1, block) * np.exp(v), axis=1)
    carry, into = 0.0, []
    for end, fade in zip(local[:, -1].tolist(), np.exp(-v[:, -1]).tolist()):
        into.append(carry)
        carry = end + carry * fade
    return (local + np.asarray(into)[:, None] * np.exp(-v)).ravel()[:n]


def dahl_in_series(x: np.ndarray, torque: float, stiffness: float, k: float) -> np.ndarray:
    """Dahl hysteresis torque z (Nm) of a loop in parallel with a linear spring k (Nm/rad) when the pair carries
    k x (x in rad, a 1-D record): k d + z(d) = k x, z the Dahl torque of the deflection d = x - z / k.

    Where x moves one way (sign s), dz/dx = k sigma w / (k + sigma w) with w = 1 - s z / tau_h, so y = (sigma / k) w
    keeps y + ln y + sigma s x / tau_h constant: y follows from its value where the stretch starts by the Wright
    omega function (the y solving y + ln y = c), and w turns into 2 - w at a reversal (z is continuous). For
    sigma << k this is `dahl` of x; here the loop may be stiffer than the spring (it then holds the deflection
    still after a reversal until it slips).
    """
    r = stiffness / k
    step = np.diff(x, prepend=x[0])
    s = np.sign(step)
    moving = np.flatnonzero(s)
    if moving.size == 0:
        return np.zeros_like(x)
    s[: moving[0]] = s[moving[0]]  # a sample that does not move keeps the direction it came from
    s = s[np.maximum.accumulate(np.where(s != 0, np.arange(s.size), 0))]
    spent = np.cumsum(np.abs(step)) * (stiffness / torque)  # running sum of sigma |dx| / tau_h
    starts = np.flatnonzero(np.diff(s, prepend=0.0))
    ends = np.append(starts[1:], x.size) - 1
    before = np.where(starts > 0, spent[starts - 1], 0.0)
    z, offsets = 0.0, []  # y + ln y = offset - spent along each stretch
    for sign, b0, end in zip(s[starts].tolist(), before.tolist(), spent[ends].tolist()):
        y0 = r * (1.0 - sign * z / torque)
        offsets.append((y0 + math.log(y0) if y0 > 0 else -math.inf) + b0)
        z = sign * torque * (1.0 - float(wrightomega(offsets[-1] - end)) / r)
    level = np.repeat(offsets, ends - starts + 1) - spent
    return s * torque * (1.0 - wrightomega(level) / r)


class DahlHysteresis(Effect):
    """Rate-independent hysteresis (Dahl): torque += z, dz/dd = sigma (1 - z sign(d')/tau_h).

    z saturates at +-tau_h; the loop stays open at any rate. Discretised exactly for a
    monotonic deflection step: z -> s tau_h + (z - s tau_h) exp(-sigma |dd| / tau_h). `apply`
    solves the recursion block-wise (`dahl`), `step` one sample at a time.
    """

    key = "hysteresis"
    summary = "Dahl hysteresis torque z with dz/dd = sigma (1 - z sign(dd)/tau_h)"
    signature = "loop vs deflection that stays open at low frequency"
    parameters = (
        Param("torque_Nm", "Nm", 0.3, 1e-6, 20.0, "saturation torque tau_h of the hysteresis loop"),
        Param("stiffness_Nm_per_rad", "Nm/rad", 50.0, 1e-3, 1e5, "initial slope sigma after a reversal"),
    )
    reads = ("deflection",)
    writes = "torque"
    stateful = True
    log_params = ("torque_Nm", "stiffness_Nm_per_rad")

    def _init(self, x, p, xp=np):
        return {"z": xp.zeros_like(x["deflection"]), "d": x["deflection"]}

    def _advance(self, state, x, dt, p, xp=np, options=EXACT):
        d = x["deflection"]
        step = d - state["d"]
        th = p["torque_Nm"]
        s = xp.sign(step)
        z = s * th + (state["z"] - s * th) * xp.exp(-p["stiffness_Nm_per_rad"] * xp.abs(step) / th)
        return x["torque"] + z, {"z": z, "d": d}

    def _apply_stateful(self, x, p):
        d, torque = np.broadcast_arrays(x["deflection"], x["torque"])
        z = np.empty(d.shape)
        for idx in np.ndindex(d.shape[:-1]):
            z[idx] = dahl(d[idx], p["torque_Nm"], p["stiffness_Nm_per_rad"])
        return torque + z

    def search(self, s: Scales) -> Search:
        size = 0.02 * s.torque_Nm
        return ({"torque_Nm": (1e-6 * s.torque_Nm, min(20.0, s.torque_Nm)),
                 "stiffness_Nm_per_rad": (1e-3 * s.k_Nm_per_rad, 1e4 * s.k_Nm_per_rad)},
                [{"torque_Nm": size, "stiffness_Nm_per_rad": f * s.k_Nm_per_rad} for f in (3.0, 30.0)])


def sls_deflection(x: np.ndarray, dt: float, ratio: float, relaxation_s: float) -> np.ndarray:
    """Deflection d of a standard linear solid whose torque / k is x: the exact inverse of
    x = d + r (d - lowpass(d)) (r = k2 / k, uniform sample interval dt s), a linear filter."""
    a = math.exp(-dt / relaxation_s)
    b, den = [1.0, -a], [1.0 + ratio * a, -a * (1.0 + ratio)]
    d, _ = lfilter(b, den, x, zi=lfilter_zi(b, den) * x[0])
    return d


class Viscoelastic(Effect):
    """Standard linear solid: a Maxwell arm (k2 with relaxation time tr) parallel to the spring.

    torque += k2 (d - d_r), d_r' = (d - d_r)/tr: stiffer for fast motion, a loop that vanishes
    at low and high frequency, relaxation under held load.
    """

    key = "viscoelastic"
    summary = "standard linear solid: torque += k2 (d - lowpass(d, tr))"
    signature = "phase lead; loop that vanishes at low and high frequency"
    parameters = (
        Param("maxwell_stiffness_Nm_per_rad", "Nm/rad", 3.0, 0.0, 1e5, "stiffness k2 of the Maxwell arm"),
        Param("relaxation_time_s", "s", 0.2, 1e-4, 1e4, "relaxation time tr = damper / k2"),
    )
    reads = ("deflection", "time")
    writes = "torque"
    stateful = True
    log_params = ("relaxation_time_s",)

    def _init(self, x, p, xp=np):
        return {"relaxed": x["deflection"]}

    def _advance(self, state, x, dt, p, xp=np, options=EXACT):
        d = x["deflection"]
        relaxed = state["relaxed"] + (d - state["relaxed"]) * (1.0 - math.exp(-dt / p["relaxation_time_s"]))
        return x["torque"] + p["maxwell_stiffness_Nm_per_rad"] * (d - relaxed), {"relaxed": relaxed}

    def _apply_stateful(self, x, p):
        relaxed = lowpass(x["deflection"], x["time"], p["relaxation_time_s"])
        return x["torque"] + p["maxwell_stiffness_Nm_per_rad"] * (x["deflection"] - relaxed)

    def search(self, s: Scales) -> Search:
        # relaxation faster than 0.1 s or ten samples is not told from a filter of the noise, one slower than half the
        # record is a stiffness and an offset
        return ({"maxwell_stiffness_Nm_per_rad": (0.0, 10.0 * s.k_Nm_per_rad),
                 "relaxation_time_s": (max(10 * s.dt_s, 0.1), max(0.5 * s.duration_s, 0.2))},
                [{"maxwell_stiffness_Nm_per_rad": 0.1 * s.k_Nm_per_rad, "relaxation_time_s": tr} for tr in (0.05, 0.5, 5.0)])


def leaky_sum(h: np.ndarray, dt: float, tau: float) -> np.ndarray:
    """s_n = s_{n-1} exp(-dt/tau) + h_n at a uniform sample interval dt (s): heat with cooling time tau (s)."""
    return lfilter([1.0], [1.0, -math.exp(-dt / tau)], h)


def softening_marched(work: np.ndarray, dt: float, c: float, tc: float, compliance: bool,
                      chunk: int | None = None) -> np.ndarray:
    """Stiffness factor f per sample of `ThermalSoftening`, marched in chunks of `chunk` samples (default:
    25, or 1/200 of the record if longer) at a uniform sample interval dt (s), f constant within a chunk and
    solved implicitly there (closed form).

    `work` per sample: |torque dd| with the torque of the unsoftened spring (stiffness direction, where the
    deflection d is known: the spring takes f times that) or |torque dx| with x = torque / k (compliance
    direction, where the torque is known and the true deflection is x / f: the spring takes that over f).
    With H_s the heat carried into a chunk and S its work: f = 1 - c (H_s + S f), or f = 1 - c (H_s + S / f)
    (the larger root of f^2 - (1 - c H_s) f + c S = 0; none: the spring runs away, f = 0.05). The
    chunking keeps it stable where a whole-record fixed point diverges (past a third of softening).
    """
    a = math.exp(-dt / tc)
    chunk = chunk or max(25, work.size // 200)
    filled = leaky_sum(work, dt, tc)
    ends = np.append(np.arange(chunk - 1, work.size - 1, chunk), work.size - 1)
    per_chunk = np.empty(ends.size)
    heat, prev = 0.0, -1
    for j, e in enumerate(ends.tolist()):
        decay = a ** (e - prev)
        start = heat * decay
        gained = filled[e] - (decay * filled[prev] if prev >= 0 else 0.0)
        left = 1.0 - c * start
        if compliance:
            disc = left * left - 4.0 * c * gained
            f = 0.5 * (left + math.sqrt(disc)) if disc >= 0 and left > 0 else 0.05
        else:
            f = left / (1.0 + c * gained)
        f = min(max(f, 0.05), 1.0)
        heat, prev = start + gained * (1.0 / f if compliance else f), e
        per_chunk[j] = f
    f_chunk = np.repeat(per_chunk, np.diff(np.concatenate([[-1], ends])))
    taken = work / f_chunk if compliance else work * f_chunk
    return np.maximum(1.0 - c * leaky_sum(taken, dt, tc), 0.05)


class ThermalSoftening(Effect):
    """Stiffness falls with the heat the spring keeps: torque *= f = 1 - c H, floored at 0.05.

    H' = |torque d'| - H / tc: the mechanical power the spring takes (its softened torque times its
    deflection rate) heats it, and it cools with time constant tc. c = a eta / C folds the relative
    stiffness loss a per kelvin, the share eta of the power lost as heat and the heat capacity C (J/K)
    into the one gain that data can identify (e.g. a = 0.01 /K, eta = 0.1, C = 15 J/K: c = 6.7e-5 /J).
    Per sample, implicitly: H_n = H_{n-1} exp(-dt/tc) + f_n |t_n dd_n| with t_n the unsoftened torque.
    """

    key = "thermal_softening"
    summary = "torque *= 1 - c H, H' = |torque d'| - H / tc"
    signature = "drift that tracks cumulative dissipated energy"
    parameters = (
        Param("softening_per_J", "1/J", 6.7e-5, 0.0, 1.0, "relative stiffness loss c per joule of heat kept"),
        Param("cooling_time_s", "s", 600.0, 1.0, 1e6, "time constant tc of cooling to ambient"),
    )
    reads = ("deflection", "time")
    writes = "torque"
    stateful = True
    log_params = ("cooling_time_s",)

    def _init(self, x, p, xp=np):
        return {"heat": xp.zeros_like(x["deflection"]), "d": x["deflection"]}

    def _advance(self, state, x, dt, p, xp=np, options=EXACT):
        d, tau, c = x["deflection"], x["torque"], p["softening_per_J"]
        kept = state["heat"] * math.exp(-dt / p["cooling_time_s"])
        work = xp.abs(tau * (d - state["d"]))
        f = xp.maximum((1.0 - c * kept) / (1.0 + c * work), 0.05)
        return tau * f, {"heat": kept + f * work, "d": d}

    def _apply_stateful(self, x, p):
        c, tc = p["softening_per_J"], p["cooling_time_s"]
        d, tau = np.broadcast_arrays(x["deflection"], x["torque"])
        out = np.empty(np.broadcast_shapes(d.shape, np.shape(x["time"])))
        flat = out.reshape(-1, out.shape[-1])
        for i, (ds, ts, dts) in enumerate(rows(d, tau, time_steps(x["time"]))):
            heat, prev, ys = 0.0, ds[0], []
            for dv, tv, step in zip(ds, ts, dts):
                kept = heat * math.exp(-step / tc)
                work = abs(tv * (dv - prev))
                f = max((1.0 - c * kept) / (1.0 + c * work), 0.05)
                heat, prev = kept + f * work, dv
                ys.append(tv * f)
            flat[i] = ys
        return out

    def search(self, s: Scales) -> Search:
        return ({"softening_per_J": (0.0, 1.0), "cooling_time_s": (1.0, 1e6)},
                [{"softening_per_J": 1e-3, "cooling_time_s": tc} for tc in (30.0, 300.0, 3000.0)])


class TemperatureSoftening(Effect):
    """Stiffness falls with a measured temperature: torque *= 1 - a (T - T0), floored at 0.05."""

    key = "temperature_softening"
    summary = "torque *= 1 - a (T - T0) from a measured temperature"
    signature = "drift that tracks temperature"
    parameters = (
        Param("softening_per_K", "1/K", 0.01, 0.0, 0.05, "relative stiffness loss a per kelvin"),
        Param("reference_temperature_C", "degC", 23.0, -40.0, 150.0, "temperature T0 at which k holds"),
    )
    reads = ("temperature",)
    writes = "torque"

    def _map(self, x, p, rng, xp=np, options=EXACT):
        factor = 1.0 - p["softening_per_K"] * (x["temperature"] - p["reference_temperature_C"])
        return x["torque"] * xp.maximum(factor, 0.05)

    def search(self, s: Scales) -> Search:
        t0 = s.temperature_C  # held at the first sample's temperature: T0 and a stiffness scale are one freedom
        return ({"softening_per_K": (0.0, 0.05), "reference_temperature_C": (t0, t0)},
                [{"softening_per_K": 0.005, "reference_temperature_C": t0}])
