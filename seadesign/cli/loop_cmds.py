"""`seadesign explain`: close the loop between a model and measured data."""

from __future__ import annotations

from pathlib import Path

import click

from seadesign.cli import main
from seadesign.errors import ConfigError
from seadesign.design.spring import load_spring
from seadesign.calibration import CANDIDATES, ROLES
from seadesign.calibration.explain_file import explain_file
from seadesign.constants import THESIS_K_MEASURED_NM_PER_RAD
from seadesign.calibration.thesis import K_FEA_NM_PER_RAD, worked_example

#: older role names the generic table's --signal still accepts (the loop's vocabulary is the effect library's)
_ROLE_ALIASES = {"displacement": "deflection"}


def _pairs(items: tuple[str, ...], option: str) -> dict[str, str]:
    out = {}
    for item in items:
        role, eq, col = item.partition("=")
        role = _ROLE_ALIASES.get(role, role)
        if not eq or not col:
            raise ConfigError(f"{option} '{item}' must be ROLE=VALUE, e.g. deflection=deflection_rad")
        if option == "--signal" and role not in ROLES:
            raise ConfigError(f"{option} '{item}': unknown role '{role}'; roles: {', '.join(ROLES)}")
        out[role] = col
    return out


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
@click.option("--law", type=click.Choice(["auto", "scale", "mooney_rivlin", "yeoh"]), default="auto", show_default=True,
              help="Bench files with a torque curve: trace the material law's shape beside its scale (auto: "
                   "Mooney-Rivlin C01 and Yeoh C20; recomputes the spring's part for trial laws, so its study must "
                   "load and still give spring.json's curve), or fit the scale alone (scale).")
def explain_cmd(file: Path, spring_path: Path | None, json_out: Path | None, out_dir: Path, predict: str, knee: str,
                keep_lifted: bool | None, measured: str | None, predicted: str | None, signals: tuple[str, ...],
                units: tuple[str, ...], measured_unit: str, declare: tuple[str, ...], plain: bool,
                min_gain: float, law: str) -> None:
    """Explain the residual between a model and measured FILE: the declared model refitted, missing effects,
    error before and after.

    FILE is a bench file or robot recording (with --spring), or any CSV table with --measured,
    --predicted and --signal ROLE=COLUMN.
    """
    generic = bool(measured and predicted)  # one without the other: the library names what is missing
    found = explain_file(file, spring_path, out_dir=out_dir, json_out=json_out, predict=predict, knee=knee,
                         keep_lifted=keep_lifted, measured=measured, predicted=predicted,
                         signals=_pairs(signals, "--signal") if generic else None,
                         units=_pairs(units, "--unit") if generic else None, measured_unit=measured_unit,
                         declare=declare, plain=plain, min_gain=min_gain, law=law)
    for line in found.lines():
        click.echo(line)


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
