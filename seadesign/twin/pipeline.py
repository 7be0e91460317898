"""The simulators as `seadesign simulate` and `seadesign simulate-bench` run them, for ``import seadesign as sd``:
a spring (spring.json or its content) in, a table and its metadata out. The caller writes them
(`seadesign.data.write_recording`, `seadesign.data.write_bench`); the metadata holds every effect and setting."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from seadesign.design.spring import load_spring, torque_curve, validate_spring
from seadesign.twin.bench import BenchProtocol, simulate_bench
from seadesign.twin.config import KneeConfig, bench_effects, configure_chain, knee_effects
from seadesign.twin.knee import KneeSession
from seadesign.twin.walk import thesis_protocol

if TYPE_CHECKING:
    import pandas as pd


def _spring(spring: str | Path | dict[str, Any]) -> tuple[dict[str, Any], dict[str, str]]:
    """The spring's content, and the metadata entry naming its file (none for a dict)."""
    if isinstance(spring, (str, Path)):
        return load_spring(spring), {"spring_file": str(spring)}
    return validate_spring(spring, "the spring given"), {}


def simulate_walk(spring: str | Path | dict[str, Any], *, ground: bool = False, seed: int = 0, rate_hz: float = 100.0,
                  trial_duration_s: float = 10.0, repeats: int = 1,
                  effects: tuple[str, ...] = ()) -> tuple[pd.DataFrame, dict[str, Any]]:
    """Both knees of the robot walking the thesis protocol (6 directions x 0.05/0.1/0.2 m/s) with the spring.

    Parameters
    ----------
    spring : str, Path or dict
        A spring.json (k, servo and robot data are read from it) or its content.
    ground : bool
        Walk on the ground (True) or hang (False).
    seed : int
        Random seed of the noise.
    rate_hz : float
        Sample rate (Hz).
    trial_duration_s : float
        Length of each trial (s).
    repeats : int
        Times the protocol is repeated.
    effects : tuple of str
        Effects switched or set, as `--effect`: ``NAME`` (on), ``NAME=off``, ``NAME:param=value,...``.

    Returns
    -------
    pandas.DataFrame
        The recording in the robot format's columns.
    dict
        Its metadata: settings, versions, seed, trials, every effect (on and off) and the spring file.

    Raises
    ------
    SpringFileError
        The spring is missing or does not match the spring.json schema (the message names the field).
    ConfigError
        An effect or its parameter is unknown or out of range.

    Examples
    --------
    >>> import seadesign as sd
    >>> from seadesign.data import write_recording
    >>> table, meta = sd.simulate("exports/wolfgang_knee/spring.json", ground=True)
    >>> write_recording(table, "walk.csv", meta)
    """
    data, named = _spring(spring)
    config = KneeConfig.from_spring(data)
    session = KneeSession(data, thesis_protocol(trial_duration_s, repeats), ground=ground, rate_hz=rate_hz, seed=seed,
                          effects=configure_chain(knee_effects(config, ground), list(effects)), config=config)
    table = session.run()
    return table, {**session.metadata(), **named}


def simulate_bench_test(spring: str | Path | dict[str, Any], *, profile: str = "sine", torque_amplitude_Nm: float = 4.8,
                        frequency_hz: float = 0.05, duration_s: float = 120.0, rate_hz: float = 100.0, seed: int = 0,
                        effects: tuple[str, ...] = ()) -> tuple[pd.DataFrame, dict[str, Any]]:
    """A torque-deflection bench test of the spring.

    Parameters
    ----------
    spring : str, Path or dict
        A spring.json or its content; the rotation is read from its torque curve when it has one, else from k.
    profile : {"sine", "ramp"}
        Drive profile: a sine or a triangular ramp.
    torque_amplitude_Nm : float
        Peak spring torque of the drive (Nm).
    frequency_hz : float
        Drive frequency (Hz).
    duration_s : float
        Test length (s).
    rate_hz : float
        Sample rate (Hz).
    seed : int
        Random seed of the noise.
    effects : tuple of str
        Effects switched or set, as `--effect`.

    Returns
    -------
    pandas.DataFrame
        ``time_s``, ``torque_Nm``, ``deflection_rad``.
    dict
        Its metadata: settings, every effect and the spring file.

    Raises
    ------
    SpringFileError
        The spring is missing or does not match the spring.json schema (the message names the field).
    ConfigError
        An unknown profile, or an effect or its parameter unknown or out of range.

    Examples
    --------
    >>> import seadesign as sd
    >>> table, meta = sd.simulate_bench("studies/thesis_measured_spring.json", effects=("dead_band",))
    """
    data, named = _spring(spring)
    chain = configure_chain(bench_effects(data["k_Nm_per_rad"], torque_curve(data)), list(effects))
    table, meta = simulate_bench(data, BenchProtocol(profile, torque_amplitude_Nm, frequency_hz, duration_s, rate_hz),
                                 effects=chain, seed=seed)
    return table, {**meta, **named}
