"""`seadesign solve`: FEA of one study candidate or of a given STL, with exports."""

from __future__ import annotations

from pathlib import Path

import click

from seadesign.cli import main
from seadesign.cli.candidate_options import candidate_options, pick_candidate
from seadesign.errors import ConfigError

_SUMMARY = (
    ("k_Nm_per_rad", "spring constant k", "Nm/rad"),
    ("stall_rotation_rad", "stall: hub rotation", "rad"),
    ("stall_bearing_displacement_mm", "stall: max displacement on the bearing circle", "mm"),
    ("stall_von_mises_max_MPa", "stall: peak von Mises", "MPa"),
    ("stall_principal_1_max_MPa", "stall: peak 1st principal", "MPa"),
    ("stall_principal_3_min_MPa", "stall: peak 3rd principal", "MPa"),
    ("stall_max_shear_max_MPa", "stall: peak max shear", "MPa"),
    ("impact_reaction_per_bolt_N", "impact: reaction per hub bolt (largest)", "N"),
    ("impact_peak_nodal_reaction_N", "impact: peak nodal reaction (mesh dependent)", "N"),
    ("impact_von_mises_max_MPa", "impact: peak von Mises", "MPa"),
    ("impact_principal_1_max_MPa", "impact: peak 1st principal", "MPa"),
    ("impact_principal_3_min_MPa", "impact: peak 3rd principal", "MPa"),
    ("impact_max_shear_max_MPa", "impact: peak max shear", "MPa"),
    ("safety_factor", "safety factor vs yield (both cases)", "-"),
    ("equilibrium_rel_error", "equilibrium: |reaction + applied| / applied torque", "-"),
    ("mesh_tets", "tetrahedra", "-"),
    ("dofs", "degrees of freedom (P2)", "-"),
    ("time_total_s", "wall time", "s"),
)


@main.command()
@click.argument("study", required=False)
@candidate_options
@click.option("--stl", "stl", type=click.Path(dir_okay=False, path_type=Path), help="Solve this STL (mm) instead.")
@click.option("--axis", type=click.Choice(["x", "y", "z"]), default="y", show_default=True, help="STL spring axis.")
@click.option("--beam-width-mm", type=float, help="STL: beam width that sets the mesh size.")
@click.option("--material", help="Material: a name (NAME.toml here, else the packaged one) or a path; default: the study's, ninjaflex for --stl.")
@click.option("--material-E-Pa", "youngs", type=float, help="Override Young's modulus (Pa).")
@click.option("--material-nu", "nu", type=float, help="Override Poisson ratio.")
@click.option("--material-yield-Pa", "yield_", type=float, help="Override yield strength (Pa).")
@click.option("--stall-torque-Nm", type=float, help="Default: the study's (for --stl: the default study's).")
@click.option("--impact-torque-Nm", type=float, help="Default: the study's (for --stl: the default study's).")
@click.option("--bearing-radius-mm", type=float, help="Default: the study's; for --stl the detected hub radius.")
@click.option("--elements-across-beam", type=float, help="Mesh density; default: the study's (3 for --stl).")
@click.option("--elements-per-circle", type=click.FloatRange(min=0), default=None,
              help="gmsh: elements per full turn on curved surfaces (holes, fillets); default: the study's (0 = "
                   "uniform, the only choice for pytetwild).")
@click.option("--backend", type=click.Choice(["gmsh", "pytetwild"]), help="Mesher; default: the study's (STL: pytetwild).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              help="Where to write NAME.json and NAME.vtu; default exports/<study or STL name>/.")
@click.option("--export-ccx", "ccx_dir", type=click.Path(file_okay=False, path_type=Path),
              help="Also write CalculiX decks stall.inp and impact.inp here.")
def solve(study, beams, thickness_mm, param, stl, axis, beam_width_mm, material, youngs, nu, yield_, stall_torque_nm,
          impact_torque_nm, bearing_radius_mm, elements_across_beam, elements_per_circle, backend, out_dir, ccx_dir) -> None:
    """Mesh and solve the stall and impact load cases of one part; print and write the results.

    Either STUDY and the candidate's design-axis values (--param KEY=VALUE, or --beams N
    --thickness-mm T), or --stl FILE --beam-width-mm W.
    """
    from seadesign.design.study import load_study
    from seadesign.sweep.single import solve_candidate, solve_stl

    if (stl is None) == (study is None):
        raise ConfigError("give either a STUDY (with its candidate's axis values) or --stl FILE, not both or neither")
    st = load_study(study) if study is not None else load_study()
    overrides = dict(youngs_modulus_Pa=youngs, poisson_ratio=nu, yield_strength_Pa=yield_,
                     stall_torque_Nm=stall_torque_nm, impact_torque_Nm=impact_torque_nm,
                     bearing_radius_mm=bearing_radius_mm, export_ccx_dir=ccx_dir)
    if stl is not None:
        if beam_width_mm is None:
            raise ConfigError("--stl needs --beam-width-mm (the beams' in-plane width sets the mesh size)")
        out_dir = out_dir or Path("exports") / stl.stem
        solved = solve_stl(stl, beam_width_mm, study=st, axis=axis, out_dir=out_dir, material=material or "ninjaflex",
                           elements_across_beam=elements_across_beam or 3.0, backend=backend or "pytetwild",
                           elements_per_circle=elements_per_circle or 0.0, **overrides)
    else:
        out_dir = out_dir or Path("exports") / st.name
        solved = solve_candidate(st, pick_candidate(st, beams, thickness_mm, param), out_dir=out_dir,
                                 material=material, elements_across_beam=elements_across_beam,
                                 elements_per_circle=elements_per_circle, backend=backend, **overrides)
    per_circle = solved.elements_per_circle
    click.echo(f"{solved.name}: {solved.material.name}, mesh {solved.backend} at {solved.elements_across_beam:g} "
               f"elements across {solved.beam_width_mm:g} mm"
               + (f", {per_circle:g} per turn on curved surfaces" if per_circle else ""))
    for key, label, unit in _SUMMARY:
        click.echo(f"  {label:<52} {solved.results[key]:>12.5g} {unit}")
    click.echo(f"written: {out_dir / (solved.name + '.json')}, {out_dir / (solved.name + '.vtu')}")
    if ccx_dir is not None:
        click.echo(f"CalculiX decks: {Path(ccx_dir) / 'stall.inp'}, {Path(ccx_dir) / 'impact.inp'} (run: ccx -i stall)")
