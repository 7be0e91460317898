"""Design-side subcommands: init, geometry, export."""

from __future__ import annotations

from pathlib import Path

import click

from seadesign.cli import main
from seadesign.cli.candidate_options import candidate_options, pick_candidate
from seadesign.design.study import DEFAULT_STUDY, load_study

_STUDY_ARG = click.argument("study", default=str(DEFAULT_STUDY.stem), required=False)
_OUT_OPT = click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), default=Path("exports"),
                       show_default=True, help="Output root; files go to OUT/<study>/.")
_TOL_OPT = click.option("--tolerance-mm", type=click.FloatRange(min=1e-4, max=1.0), default=0.01, show_default=True,
                       help="STL chordal tolerance in mm (max distance between triangles and the true surface).")


@main.command()
@_STUDY_ARG
def geometry(study: str) -> None:
    """List every candidate of STUDY (a name: NAME.toml here, else the packaged study; or a path): valid or not,
    why, volume and mass.

    Volume in mm^3, mass in g (from the candidate material's density).
    """
    s = load_study(study)
    candidates = s.candidates()
    click.echo(f"study {s.name}: {len(candidates)} candidates, material {', '.join(m.name for m in s.materials.values())}")
    width = max(len("candidate"), *(len(c.name) for c in candidates))
    click.echo(f"{'candidate':<{width}} {'valid':>5} {'volume_mm3':>11} {'mass_g':>7}  reason")
    for candidate in candidates:
        c, _ = s.check(candidate)
        click.echo(f"{c.name:<{width}} {'yes' if c.valid else 'no':>5} {c.volume_mm3:>11.1f} {1000 * c.mass_kg:>7.2f}  "
                   f"{'; '.join(c.reasons)}")


@main.command()
@_STUDY_ARG
@candidate_options
@_TOL_OPT
@_OUT_OPT
def export(study: str, beams: int | None, thickness_mm: float | None, param: tuple[str, ...], tolerance_mm: float,
           out_dir: Path) -> None:
    """Write STL and STEP (mm) of one valid candidate of STUDY to OUT/<study>/ (the candidate by its
    design-axis values: --param KEY=VALUE, or --beams N --thickness-mm T)."""
    from seadesign.api import export as export_design

    s = load_study(study)
    for path in export_design(s, pick_candidate(s, beams, thickness_mm, param), out_dir, tolerance_mm):
        click.echo(f"wrote {path}")


@main.command()
@click.argument("folder", type=click.Path(file_okay=False, path_type=Path), default=Path("."), required=False)
@click.option("--force", is_flag=True, help="Overwrite the files if they exist.")
def init(folder: Path, force: bool) -> None:
    """Write a study and a material to start from into FOLDER (default: here), commented copies of the
    packaged default study and its material. Run from FOLDER, commands read them before the packaged files."""
    from seadesign.design.starter import write_starters

    study, material = write_starters(folder, force)
    click.echo(f"wrote {study} (study) and {material} (material); edit them, then run "
               f"`seadesign geometry {study.stem}` in {folder}")
