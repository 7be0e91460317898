"""Mesh convergence of the large-deflection path: the curve, the contact onset and the peak strain.

Usage: python benchmarks/path_convergence.py [--study wolfgang_knee] [--candidates 8x4,3x8]
       [--meshes 2,path,1] [--rotations 0.1,0.2,0.3] [--max-step-rad 0.004] [--strain-levels 0.1,0.2,0.3,0.433]
       [--contact]
Prints, per candidate and mesh (a number: that coarsening of the study's mesh, 1 being the result mesh;
"path": the sweep's path mesh, the result mesh's in-plane sizing with SolverSettings.path_layers layers
through the thickness; the finest last), the degrees of freedom, the torque at each listed rotation (Nm), where and why the path stops
(rad, Nm), the torque where the peak tensile strain passes the single-event limit (elongation at yield / safety
factor), the peak tensile strain at the first listed rotation, the time, and each number's difference to the
coarsest mesh's as each mesh finishes (a run stopped early keeps its rows), then the table again against the
finest. Contact and strain peaks sit at beam roots (fillets), so they converge more slowly than the torque.

`--strain-levels` also prints, per mesh, the torque (Nm) where the peak tensile strain reaches each level, and
at the end the path mesh's largest overestimate of those torques against the finest mesh over every candidate
and level: the knock-down the sweep applies to the path's strain-limit torques (`sweep.requirements.
STRAIN_TORQUE_KNOCKDOWN`).

`--contact`: the path goes on through frictionless self-contact (`fea.rotation_path.through_contact`, the sweep's
setting); each mesh's row then also gives first contact (rad, Nm), why and where contact
ended the path if it ended unconverged, and at the last listed rotation the peak tensile strain with its distance
(mm, at rest) from where the contact presses hardest: the strain in the contact zone when that distance is small.
`--docs` then writes docs/validation/_fragments/path_convergence_contact.md, or with more than one mesh
path_convergence_contact_meshes.md (one candidate's meshes against each other).

`--docs` writes the table against the finest mesh (docs/validation/_fragments/path_convergence.md) and, with
`--strain-levels`, the torques at each strain level (strain_knockdown.md).
"""

from __future__ import annotations

import argparse

import numpy as np
from record import Table, add_docs_option, machine, write_fragment

from seadesign.design.study import load_study
from seadesign.fea.large_deflection import element_location, large_deflection
from seadesign.fea.rotation_path import PathSettings, rotation_path, through_contact
from seadesign.run.cache import Cache
from seadesign.sweep.stages import SolverSettings, check_geometry, tetrahedralize


def _number(value: float | None) -> float:
    return float("nan") if value is None else value


def strain_at(path, theta: float) -> float:
    return float(np.interp(theta, [p.rotation_rad for p in path.points], [p.peak_tensile_strain for p in path.points],
                           right=np.nan))


def torque_at_strain(path, level: float) -> float:
    """The torque (Nm) where the peak tensile strain, linear between the path's points, first reaches `level`."""
    strain = np.array([p.peak_tensile_strain for p in path.points])
    above = np.flatnonzero(strain >= level)
    if not above.size or above[0] == 0:
        return float("nan")
    i = int(above[0])
    s = (level - strain[i - 1]) / (strain[i] - strain[i - 1])
    return float(path.points[i - 1].torque_Nm + s * (path.points[i].torque_Nm - path.points[i - 1].torque_Nm))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--study", default="wolfgang_knee")
    ap.add_argument("--candidates", default="8x4,3x8", help="beams x thickness_mm, comma separated")
    ap.add_argument("--meshes", default="2,path,1", help="edge-length factors on the study's mesh, or path")
    ap.add_argument("--rotations", default="0.1,0.2,0.3", help="rotations (rad) where the torque is compared")
    ap.add_argument("--strain-levels", default="", help="tensile strains (-) whose torques are compared, comma "
                                                            "separated, e.g. 0.1,0.2,0.3,0.433")
    ap.add_argument("--study-candidate", default="", help="one design of --study by its axis values, KEY=VALUE;... "
                                                           "(for a study with continuous axes)")
    ap.add_argument("--max-step-rad", type=float, default=PathSettings().max_step_rad,
                    help="the path's largest step (rad): smaller steps check that no narrow instability is stepped over")
    ap.add_argument("--contact", action="store_true", help="through frictionless self-contact (the sweep's "
                    "setting)")
    add_docs_option(ap, "path_convergence", "strain_knockdown", "path_convergence_contact",
                    "path_convergence_contact_meshes")
    args = ap.parse_args()
    settings = PathSettings(max_step_rad=args.max_step_rad)
    settings = through_contact(settings) if args.contact else settings
    st = load_study(args.study)
    cache = Cache()
    meshes = args.meshes.split(",")
    rotations = [float(r) for r in args.rotations.split(",")]
    levels = [float(x) for x in args.strain_levels.split(",") if x]
    ratios = []  # (candidate, level, path-mesh torque / finest-mesh torque)
    print(f"machine: {machine()}")
    print(f"study {st.name}, path settings {settings}")
    convergence = Table(["design", "mesh", "dofs", f"T at {' / '.join(f'{r:g}' for r in rotations)} rad (Nm)",
                         "stop (rad, Nm)", "single-event strain limit passed at (Nm)",
                         f"peak tensile strain at {rotations[0]:g} rad", "time (s)"])
    through = Table(["design", "mesh", "dofs", f"T at {' / '.join(f'{r:g}' for r in rotations)} rad (Nm)",
                     "first contact (rad, Nm)", "end (why, rad, Nm)",
                     "contact ended it: why, where (x, y, z mm)",
                     f"peak tensile strain at {rotations[-1]:g} rad (distance to the contact's peak, mm)"])
    knockdown = Table(["design", f"torque (Nm) at tensile strain {' / '.join(f'{x:g}' for x in levels)}, path mesh",
                       f"mesh {meshes[-1]}", f"path / mesh {meshes[-1]}"])
    specs = [args.study_candidate] if args.study_candidate else args.candidates.split(",")
    for spec in specs:
        if args.study_candidate:
            values = dict(kv.split("=") for kv in spec.split(";"))
            chosen = st.candidate(**{k: v if k == "material" else float(v) if "." in v else int(v)
                                     for k, v in values.items()})
        else:
            n, t = spec.split("x")
            chosen = st.candidate(beam_count=int(n), beam_thickness_mm=float(t))
        candidate, part = check_geometry(st, chosen, cache)
        part = part or st.check(candidate)[1]
        m, lc = candidate.material, st.load_cases
        print(f"\n{candidate.name}: material {m.name} ({m.law.model}, C10 {m.law.c10_Pa / 1e6:.3g} MPa, D1 "
              f"{m.law.d1_per_Pa * 1e6:.3g} 1/MPa)")
        print(f"\n{candidate.name}: torque (Nm) at {', '.join(f'{r:g}' for r in rotations)} rad; stop; strain limit "
              f"torque (Nm); peak strain at {rotations[0]:g} rad; in brackets: relative difference to the first "
              f"(coarsest) mesh, then the table again against the finest", flush=True)
        rows, at_levels = [], {}
        for c in meshes:
            mesh = (tetrahedralize(st, candidate, part, cache, layers=SolverSettings().path_layers) if c == "path"
                    else tetrahedralize(st, candidate, part, cache, float(c)))
            path = rotation_path(mesh, m.law, lc.impact_torque_Nm, settings)
            ld = large_deflection(path, st.robot.standing_knee_torque_Nm, lc.stall_torque_Nm, lc.impact_torque_Nm,
                                  m.strain_limits(st.ranking.safety_factor))
            rows.append((c, ld.dofs, [_number(path.torque_at(r)) for r in rotations], path.stop_reason,
                         ld.stop_rotation_rad, ld.stop_torque_Nm, ld.single_limit_torque_Nm,
                         strain_at(path, rotations[0]), path.time_s))
            _print_row(rows[-1], rows[0])  # as it comes: a long run leaves its coarse rows
            if args.contact:
                through.add(candidate.name, c, f"{ld.dofs:,}",
                            " / ".join(f"{v:.4g}" if np.isfinite(v) else "not reached" for v in rows[-1][2]),
                            *_contact_cells(path, ld, rotations[-1]))
                print("    " + "; ".join(through.rows[-1][4:]), flush=True)
            if levels:
                at_levels[c] = [torque_at_strain(path, x) for x in levels]
                print("    torque (Nm) at tensile strain " + ", ".join(f"{x:g}: {v:.4g}" for x, v in
                                                                       zip(levels, at_levels[c])), flush=True)
        if levels and "path" in at_levels and meshes[-1] != "path":
            for x, tp, tf in zip(levels, at_levels["path"], at_levels[meshes[-1]]):
                if np.isfinite(tp) and np.isfinite(tf):
                    ratios.append((candidate.name, x, tp / tf))
        print("  against the finest:")
        for row in rows:
            _print_row(row, rows[-1])
            convergence.add(candidate.name, row[0], f"{row[1]:,}", *_cells(row, rows[-1]))
        if levels and "path" in at_levels and meshes[-1] != "path":
            path_t, fine_t = at_levels["path"], at_levels[meshes[-1]]
            knockdown.add(candidate.name, " / ".join(f"{v:.4g}" for v in path_t),
                          " / ".join(f"{v:.4g}" for v in fine_t),
                          " / ".join(f"{a / b:.4f}" if np.isfinite(a / b) else "-" for a, b in zip(path_t, fine_t)))
    if ratios:
        name, level, worst = max(ratios, key=lambda r: r[2])
        print("\npath mesh / finest mesh, torque at each tensile strain: " + "; ".join(
            f"{n} at {x:g}: {r:.4f}" for n, x, r in ratios))
        print(f"largest path-mesh overestimate: {name} at strain {level:g}: x {worst:.4f}; knock-down on the path's "
              f"strain-limit torques: {min(1.0, 1.0 / worst):.4f}")
    if args.docs and args.contact:  # candidates on one mesh, or one candidate's meshes against each other
        contact_text = (f"Study {st.name}; meshes {args.meshes} (path: the sweep's path mesh, 1: the result mesh); "
                        "through frictionless self-contact")
        if len(meshes) > 1:
            write_fragment("path_convergence_contact_meshes", through, contact_text)
        else:
            write_fragment("path_convergence_contact", through, contact_text)
    elif args.docs:
        settings_text = (f"Study {st.name}; meshes {args.meshes} (a number: that coarsening of the study's mesh, 1 the "
                         f"result mesh; path: the sweep's path mesh); largest step {settings.max_step_rad:g} rad")
        write_fragment("path_convergence", convergence, settings_text,
                       f"In brackets: the difference to mesh {meshes[-1]}.")
        if knockdown.rows:
            write_fragment("strain_knockdown", knockdown, settings_text)


def _contact_cells(path, ld, theta: float) -> list[str]:
    """First contact, the end, why and where contact ended it, and the peak tensile strain at `theta` (rad) with its
    element's distance (mm, at rest) from the peak contact pressure of the nearest point."""
    where = ld.unconverged_at
    ended = (f"{ld.unconverged_cause} at {ld.unconverged_rotation_rad:.4f} rad, ({where.x_mm:.2f}, {where.y_mm:.2f}, "
             f"{where.z_mm:.2f})" if ld.unconverged_cause else "-")
    thetas = np.array([p.rotation_rad for p in path.points])
    strain = "not reached"
    if theta <= thetas[-1]:
        near = path.points[int(np.argmin(np.abs(thetas - theta)))]
        peak = element_location(path, near.peak_tensile_element)
        at = np.array([peak.x_mm, peak.y_mm, peak.z_mm])
        gap = (f"{np.linalg.norm(at - np.array(near.contact.peak_at_mm)):.2f}" if near.contact.area_m2 > 0
               else "no contact")
        strain = f"{strain_at(path, theta):.4g} ({gap})"
    return [f"{ld.contact_rotation_rad:.4f}, {ld.contact_torque_Nm:.4g}",
            f"{path.stop_reason}, {ld.stop_rotation_rad:.4f}, {ld.stop_torque_Nm:.4g}", ended, strain]


def _cells(row, ref) -> list[str]:
    """The table's cells of a mesh's row, each with its difference to `ref`'s."""
    c, dofs, torques, reason, stop_rad, stop_Nm, limit_Nm, strain, secs = row

    def rel(v, r):
        return f"{v:.4g} ({(v - r) / r:+.1%})" if np.isfinite(v) and np.isfinite(r) else f"{v:.4g}"

    return [" / ".join(rel(v, r) for v, r in zip(torques, ref[2])),
            f"{reason} at {rel(stop_rad, ref[4])}, {rel(stop_Nm, ref[5])}", rel(limit_Nm, ref[6]), rel(strain, ref[7]),
            f"{secs:.0f}"]


def _print_row(row, ref) -> None:
    c, dofs, torques, reason, stop_rad, stop_Nm, limit_Nm, strain, secs = row

    def rel(v, r):
        return f"{v:.4g} [{(v - r) / r:+.2%}]"

    print(f"  mesh {c:<5} {dofs:>8d} dofs  T " + ", ".join(rel(v, r) for v, r in zip(torques, ref[2]))
          + f"  stop {reason} {rel(stop_rad, ref[4])} rad {rel(stop_Nm, ref[5])} Nm  strain limit "
          f"{rel(limit_Nm, ref[6])} Nm  strain {rel(strain, ref[7])}  {secs:.0f} s", flush=True)


if __name__ == "__main__":
    main()
