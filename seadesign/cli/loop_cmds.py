"""`seadesign explain`: close the loop between a model and measured data."""

from __future__ import annotations

from pathlib import Path

import click
import pandas as pd

from seadesign.cli import main
from seadesign.data import clean, is_hanging, read_bench, read_recording
from seadesign.errors import ConfigError
from seadesign.design.spring import load_spring
from seadesign.loop import CANDIDATES, ROLES, explain, from_frame
from seadesign.loop.report import write_report
from seadesign.loop.sea import ROBOT_DECLARED, bench_loop_data, calibration, robot_declared, robot_loop_data
from seadesign.constants import THESIS_K_MEASURED_NM_PER_RAD
from seadesign.loop.thesis import K_FEA_NM_PER_RAD, worked_example

#: older role names the generic table's --signal still accepts (the loop's vocabulary is the effect library's)
ROLE_ALIASES = {"displacement": "deflection"}


def _pairs(items: tuple[str, ...], option: str) -> dict[str, str]:
    out = {}
    for item in items:
        role, eq, col = item.partition("=")
        role = ROLE_ALIASES.get(role, role)
        if not eq or not col:
            raise ConfigError(f"{option} '{item}' must be ROLE=VALUE, e.g. deflection=deflection_rad")
        if option == "--signal" and role not in ROLES:
            raise ConfigError(f"{option} '{item}': unknown role '{role}'; roles: {', '.join(ROLES)}")
        out[role] = col
    return out


def _kind(path: Path) -> str:
    header = pd.read_csv(path, nrows=0).columns
    if "l_hall_pos" in header:
        return "robot"
    if "torque_Nm" in header and "deflection_rad" in header:
        return "bench"
    raise ConfigError(f"{path}: neither a bench file (time_s, torque_Nm, deflection_rad) nor a robot recording "
                      "(l_hall_pos, ...); for another table give --measured, --predicted and --signal")


@main.command("explain")
@click.argument("file", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.option("--spring", "spring_path", type=click.Path(exists=True, dir_okay=False, path_type=Path), default=None,
              help="spring.json whose k (Nm/rad) and material make the model; needed for bench and robot files.")
@click.option("--json", "json_out", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Also write the report as JSON to this path (steps, parameters with units, errors, residual tests).")
@click.option("-o", "--out-dir", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Folder for the Markdown/HTML report, plots and calibration JSON [default: exports/explain/<FILE stem>].")
@click.option("--predict", type=click.Choice(["torque", "deflection"]), default="torque", show_default=True,
              help="Bench files: predict torque (Nm) from deflection, or deflection (rad) from torque.")
@click.option("--knee", type=click.Choice(["l", "r"]), default="l", show_default=True,
              help="Robot recordings: which knee (l left, r right; the right is un-mirrored).")
@click.option("--keep-lifted/--drop-lifted", default=None,
              help="Robot recordings: keep rows whose foot pressure sum is low (foot lifted); default: keep them "
                   "only in a hanging recording (every row low). Recordings are cleaned first (artefact rows "
                   "dropped, wrap-arounds unwrapped, Hall offsets removed at unloaded rest).")
@click.option("--measured", default=None, help="Generic table: column of the measured quantity (any unit).")
@click.option("--predicted", default=None, help="Generic table: column of the model's prediction (unit of --measured).")
@click.option("--signal", "signals", multiple=True,
              help=f"Generic table: ROLE=COLUMN, repeatable; roles: {', '.join(f'{r} ({m})' for r, m in ROLES.items())}.")
@click.option("--unit", "units", multiple=True, help="Generic table: ROLE=UNIT for the report, e.g. displacement=rad.")
@click.option("--measured-unit", default="1", show_default=True, help="Generic table: unit of --measured.")
@click.option("--declare", multiple=True, type=click.Choice(sorted(CANDIDATES)),
              help="Robot files: the declared effects to refit (dead_band = the gearbox backlash, friction = the "
                   "gear friction in the effort); default both, --declare picks only those given. Generic tables: "
                   "an effect the prediction already holds (not traced); repeatable.")
@click.option("--plain", is_flag=True, help="Robot files: declare nothing but the spring (k refitted).")
@click.option("--min-gain", type=click.FloatRange(0.0, 1.0), default=0.05, show_default=True,
              help="Relative held-out RMSE cut (fraction) an effect needs to be added.")
def explain_cmd(file: Path, spring_path: Path | None, json_out: Path | None, out_dir: Path, predict: str, knee: str,
                keep_lifted: bool | None, measured: str | None, predicted: str | None, signals: tuple[str, ...],
                units: tuple[str, ...], measured_unit: str, declare: tuple[str, ...], plain: bool,
                min_gain: float) -> None:
    """Explain the residual between a model and measured FILE: the declared model refitted, missing effects,
    error before and after.

    FILE is a bench file or robot recording (with --spring), or any CSV table with --measured,
    --predicted and --signal ROLE=COLUMN.
    """
    spring, declared, exclude = None, [], ()
    if measured or predicted:
        if not (measured and predicted):
            raise ConfigError("a generic table needs both --measured and --predicted")
        data = from_frame(pd.read_csv(file), measured, predicted, _pairs(signals, "--signal"),
                          units=_pairs(units, "--unit"), measured_unit=measured_unit)
        exclude, loop_plot, stem = tuple(declare), False, file.stem
    else:
        if spring_path is None:
            raise ConfigError(f"{file}: bench and robot files need --spring PATH (spring.json with k)")
        spring = load_spring(spring_path)
        if _kind(file) == "bench":
            data = bench_loop_data(read_bench(file), spring, predict)
            loop_plot, stem = True, file.stem
        else:
            raw = read_recording(file)
            keep = is_hanging(raw) if keep_lifted is None else keep_lifted
            table = clean(raw, keep_lifted=keep, normalise=False, euler=False).table
            data = robot_loop_data(table, spring, knee)
            declared = [] if plain else robot_declared(spring, tuple(declare) or tuple(ROBOT_DECLARED))
            loop_plot, stem = False, f"{file.stem}_{knee}"
    out_dir = out_dir or Path("exports") / "explain" / stem
    ex = explain(data, declared, exclude=exclude, min_gain=min_gain)
    cal = calibration(ex, spring, str(file)) if spring is not None else None
    paths = write_report(ex, out_dir, stem, f"Explain {file.name}", loop_plot=loop_plot, calibration=cal)
    if json_out is not None:
        json_out.parent.mkdir(parents=True, exist_ok=True)
        json_out.write_text(paths["json"].read_text())
    e0, e1 = ex.plain.errors, ex.final.errors
    click.echo(ex.verdict())
    click.echo(f"RMSE ({data.measured_unit}) train {e0['train']['rmse']:.4g} -> {e1['train']['rmse']:.4g}, "
               f"held-out {e0['held_out']['rmse']:.4g} -> {e1['held_out']['rmse']:.4g}")
    for check in ex.declared:
        click.echo(f"  declared {check.text()}")
    for key in ex.added:
        ps = ex.final.parameters().get(key, {})
        click.echo(f"  found {key}: " + ", ".join(f"{n} = {p['value']:.4g} +- {p['uncertainty']:.2g} {p['unit']}"
                                                  for n, p in ps.items()))
    for kind, path in paths.items():
        click.echo(f"{kind}: {path}")


@main.command("explain-thesis")
@click.option("--spring", "spring_path", type=click.Path(exists=True, dir_okay=False, path_type=Path), required=True,
              help="spring.json giving the actuator and robot; its k and material are replaced by the thesis FEA's.")
@click.option("-o", "--out-dir", type=click.Path(file_okay=False, path_type=Path),
              default=Path("exports") / "explain_thesis",
              show_default=True, help="Folder for the simulated bench file, report and calibration JSON.")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the simulated bench noise.")
def explain_thesis_cmd(spring_path: Path, out_dir: Path, seed: int) -> None:
    """Worked thesis example: FEA k (generic TPU) vs a bench file simulated from the measured k with a dead-band."""
    ex, cal = worked_example(load_spring(spring_path), out_dir, seed)
    click.echo(f"model k {K_FEA_NM_PER_RAD:.4g} Nm/rad (thesis FEA), bench simulated with k {THESIS_K_MEASURED_NM_PER_RAD} Nm/rad")
    click.echo(ex.verdict())
    for key, ps in ex.final.parameters().items():
        click.echo(f"  {key}: " + ", ".join(f"{n} = {p['value']:.4g} +- {p['uncertainty']:.2g} {p['unit']}"
                                             for n, p in ps.items()))
    click.echo(f"fitted k {cal['k_fitted_Nm_per_rad']:.4g} Nm/rad; re-rank the design with: "
               f"seadesign sweep --calibration {out_dir / 'thesis_calibration.json'}")
