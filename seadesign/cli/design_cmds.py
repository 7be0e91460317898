"""Design-side subcommands: geometry, export, sweep."""

from __future__ import annotations

from pathlib import Path

import click

from seadesign.design.candidate import check_candidate, find_candidate
from seadesign.cli import main
from seadesign.design.export import export_candidate
from seadesign.design.study import DEFAULT_STUDY, load_study

STUDY_ARG = click.argument("study", default=str(DEFAULT_STUDY.stem), required=False)
OUT_OPT = click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), default=Path("exports"),
                       show_default=True, help="Output root; files go to OUT/<study>/.")
TOL_OPT = click.option("--tolerance-mm", type=click.FloatRange(min=1e-4, max=1.0), default=0.01, show_default=True,
                       help="STL chordal tolerance in mm (max distance between triangles and the true surface).")


@main.command()
@STUDY_ARG
def geometry(study: str) -> None:
    """List every candidate of STUDY (name in studies/ or a path): valid or not, why, volume and mass.

    Volume in mm^3, mass in g (from the study material's density).
    """
    s = load_study(study)
    click.echo(f"study {s.name}: {len(s.candidates())} candidates, material {s.material.name}")
    click.echo(f"{'beams':>5} {'thickness_mm':>12} {'valid':>5} {'volume_mm3':>11} {'mass_g':>7}  reason")
    for params in s.candidates():
        c = check_candidate(s, params)
        click.echo(f"{params.beam_count:>5} {params.beam_thickness_mm:>12g} {'yes' if c.valid else 'no':>5} "
                   f"{c.part.volume_mm3:>11.1f} {1000 * c.mass_kg:>7.2f}  {'; '.join(c.reasons)}")


@main.command()
@STUDY_ARG
@click.option("--beams", "beam_count", type=int, required=True, help="Beam count of the candidate.")
@click.option("--thickness-mm", type=float, required=True, help="Beam thickness (in-plane width) in mm.")
@TOL_OPT
@OUT_OPT
def export(study: str, beam_count: int, thickness_mm: float, tolerance_mm: float, out_dir: Path) -> None:
    """Write STL and STEP (mm) of one valid candidate of STUDY to OUT/<study>/."""
    s = load_study(study)
    c = check_candidate(s, find_candidate(s, beam_count, thickness_mm))
    if not c.valid:
        raise click.UsageError(f"candidate {beam_count} beams x {thickness_mm:g} mm is invalid: {'; '.join(c.reasons)}")
    for path in export_candidate(c, out_dir / s.name, tolerance_mm):
        click.echo(f"wrote {path}")

