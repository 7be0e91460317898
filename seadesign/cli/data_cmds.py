"""Data subcommands: inspect and clean recordings, simulate knee and bench data."""

from __future__ import annotations

import json
import math
from pathlib import Path

import click

from seadesign import constants as C
from seadesign.cli import main
from seadesign.data import write_bench, write_cleaned, write_recording
from seadesign.data.artefacts import Thresholds
from seadesign.data.pipeline import clean_recording, inspect_recording
from seadesign.effects import EffectChain
from seadesign.twin import KneeConfig, bench_effects, knee_effects
from seadesign.twin.pipeline import simulate_bench_test, simulate_walk

EFFECT_HELP = ("Switch or set an effect: NAME (on), NAME=off, or NAME:param=value,... (parameter units as listed "
               "by `seadesign effects`); repeatable.")


@main.group()
def data() -> None:
    """Inspect and clean robot recordings."""


@data.command()
@click.argument("file", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--plot", "plot_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="PNG to write (default: <FILE stem>_inspect.png in the current folder).")
@click.option("--json", "json_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Also write the report as JSON here.")
@click.option("--step-threshold", type=float, default=Thresholds.step_threshold, show_default=True,
              help="Smallest deflection jump counted as a step, rad.")
@click.option("--gap-factor", type=float, default=Thresholds.gap_factor, show_default=True,
              help="A gap is a sample interval above this multiple of the median interval (dimensionless).")
def inspect(file: Path, plot_path: Path | None, json_path: Path | None, step_threshold: float, gap_factor: float) -> None:
    """Report the artefacts of a robot recording FILE per knee and plot them."""
    inspection = inspect_recording(file, Thresholds(step_threshold=step_threshold, gap_factor=gap_factor))
    click.echo(inspection.report.format())
    click.echo(f"plot: {inspection.plot(plot_path or Path(f'{file.stem}_inspect.png'))}")
    if json_path:
        json_path.write_text(json.dumps(inspection.report.to_dict(), indent=2) + "\n")
        click.echo(f"report: {json_path}")


@data.command(name="clean")
@click.argument("file", type=click.Path(dir_okay=False, path_type=Path))
@click.option("-o", "--output", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="Cleaned CSV to write (a <name>.meta.json sidecar holds the step log and units).")
@click.option("--pressure-threshold", type=float, default=10.0, show_default=True,
              help="Rows whose summed foot pressure (8 cells, the robot's cell units, about N) is below this are "
                   "dropped as lifted.")
@click.option("--keep-lifted", is_flag=True, help="Keep lifted rows (hanging recordings).")
@click.option("--keep-artefacts", is_flag=True, help="Keep rows with glitches and stuck Hall values.")
@click.option("--no-unwrap", is_flag=True, help="Leave Hall wrap-arounds as they are.")
@click.option("--no-offset", is_flag=True, help="Leave the Hall offset in.")
@click.option("--no-normalise", is_flag=True, help="Keep positions in rad instead of rad/pi.")
@click.option("--positive", is_flag=True, help="Mirror the right knee onto the left (thesis 'positive' dataset).")
def clean_cmd(file: Path, output: Path, pressure_threshold: float, keep_lifted: bool, keep_artefacts: bool,
              no_unwrap: bool, no_offset: bool, no_normalise: bool, positive: bool) -> None:
    """Clean a robot recording FILE as in the thesis, logging every step and removed row."""
    result = clean_recording(file, pressure_threshold=pressure_threshold, keep_lifted=keep_lifted,
                   drop_artefacts=not keep_artefacts, unwrap=not no_unwrap, remove_offset=not no_offset,
                   normalise=not no_normalise, positive=positive)
    click.echo(result.format())
    write_cleaned(result, output, str(file))
    click.echo(f"wrote {output}")


@main.command()
@click.option("--spring", "spring_path", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="spring.json to simulate (k, servo and robot data are read from it).")
@click.option("--protocol", type=click.Choice(["thesis"]), default="thesis", show_default=True,
              help="Walk protocol: thesis = 6 directions x speeds 0.05/0.1/0.2 m/s.")
@click.option("--ground/--hanging", default=False, show_default=True, help="Walk on the ground or hang.")
@click.option("--seed", type=int, default=0, show_default=True, help="Random seed (dimensionless).")
@click.option("--rate-hz", type=float, default=100.0, show_default=True, help="Sample rate, Hz.")
@click.option("--trial-duration-s", type=float, default=10.0, show_default=True, help="Length of each trial, s.")
@click.option("--repeats", type=int, default=1, show_default=True, help="Times the protocol is repeated (count).")
@click.option("--effect", "effects", multiple=True, help=EFFECT_HELP)
@click.option("-o", "--output", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="Recording CSV to write (robot format; effects and settings in <name>.meta.json).")
def simulate(spring_path: Path, protocol: str, ground: bool, seed: int, rate_hz: float, trial_duration_s: float,
             repeats: int, effects: tuple[str, ...], output: Path) -> None:
    """Simulate both knees of the robot walking the protocol with the spring in --spring."""
    df, meta = simulate_walk(spring_path, ground=ground, seed=seed, rate_hz=rate_hz, trial_duration_s=trial_duration_s,
                             repeats=repeats, effects=effects)
    write_recording(df, output, meta)
    click.echo(f"wrote {output}: {len(df)} rows, {len(meta['trials'])} trials, effects on: "
               f"{', '.join(meta['effects_enabled'])}")


@main.command(name="simulate-bench")
@click.option("--spring", "spring_path", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="spring.json whose k is tested.")
@click.option("--profile", type=click.Choice(["sine", "ramp"]), default="sine", show_default=True,
              help="Drive profile: sine or triangular ramp.")
@click.option("--torque-amplitude-nm", type=float, default=4.8, show_default=True,
              help="Peak spring torque of the drive, Nm (the rotation from the torque curve when spring.json has "
                   "one, else from k).")
@click.option("--frequency-hz", type=float, default=0.05, show_default=True, help="Drive frequency, Hz.")
@click.option("--duration-s", type=float, default=120.0, show_default=True, help="Test length, s.")
@click.option("--rate-hz", type=float, default=100.0, show_default=True, help="Sample rate, Hz.")
@click.option("--seed", type=int, default=0, show_default=True, help="Random seed (dimensionless).")
@click.option("--effect", "effects", multiple=True, help=EFFECT_HELP)
@click.option("-o", "--output", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="Bench CSV to write (time_s, torque_Nm, deflection_rad; effects in <name>.meta.json).")
def simulate_bench_cmd(spring_path: Path, profile: str, torque_amplitude_nm: float, frequency_hz: float,
                       duration_s: float, rate_hz: float, seed: int, effects: tuple[str, ...], output: Path) -> None:
    """Simulate a torque-deflection bench test of the spring in --spring."""
    df, meta = simulate_bench_test(spring_path, profile=profile, torque_amplitude_Nm=torque_amplitude_nm,
                                   frequency_hz=frequency_hz, duration_s=duration_s, rate_hz=rate_hz, seed=seed,
                                   effects=effects)
    write_bench(df, output, meta)
    click.echo(f"wrote {output}: {len(df)} rows, effects on: {', '.join(meta['effects_enabled'])}")


@main.command(name="effects")
@click.option("--bench", is_flag=True, help="List the bench simulator's chain instead of the knee's.")
def effects_cmd(bench: bool) -> None:
    """List the simulator's effects: name, on/off, parameters with units and bounds."""
    # the thesis's robot and servo, the measured k; the upper leg assumed equal to the lower (as the default study)
    cfg = KneeConfig(k_Nm_per_rad=C.THESIS_K_MEASURED_NM_PER_RAD, stall_torque_Nm=C.XH540_STALL_TORQUE_NM,
                     no_load_speed_rad_per_s=C.XH540_NO_LOAD_SPEED_RPM * 2 * math.pi / 60,
                     backlash_rad=math.radians(C.XH540_BACKLASH_DEG), mass_kg=C.WOLFGANG_MASS_KG,
                     lower_leg_m=C.WOLFGANG_LOWER_LEG_M, upper_leg_m=C.WOLFGANG_LOWER_LEG_M)
    chain: EffectChain = bench_effects(cfg.k_Nm_per_rad) if bench else knee_effects(cfg)
    for e in chain:
        click.echo(f"{e.name:20s} {'on ' if e.enabled else 'off'}  {e.summary}  [{e.key}: {' -> '.join([*map(e.signal, e.reads), e.target()])}]")
        for p in e.parameters:
            click.echo(f"{'':26s}{p.name} = {e.values[p.name]:g} {p.unit}  [{p.lower:g}, {p.upper:g}]  {p.doc}")
