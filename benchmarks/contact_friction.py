"""What frictionless contact leaves out: CalculiX with a Coulomb friction coefficient against CalculiX frictionless,
on the same mesh and contact pair, beside our (frictionless) path through contact.

Usage: python benchmarks/contact_friction.py [--beams 3] [--thickness-mm 8] [--axial-thickness-mm 9] [--coarsening 4]
       [--max-rotation-rad 0.42] [--friction 0.5] [--reach-mm 1.5] [--face-to-face]
Our path through self-contact (`fea.rotation_path.through_contact`) on the candidate's one-layer path mesh, coarsened,
to the impact torque or `--max-rotation-rad`; then CalculiX NLGEOM at the same rotations with a node-to-surface contact
pair (our penalty; the slave the nodes of the faces within `--reach-mm` of where ours touches at the end, less those on
the master faces; ccx's default residual tolerance, up to 30 iterations and 10 cutbacks an increment), frictionless and
with the friction coefficient (stick slope the penalty's). `--face-to-face`: the face-to-face pair of
`fea.ccx.write_path_inp`'s check instead (ten times our penalty, residual 1e-7), which with friction does not converge
where the pair's faces share the notch root's edge (see `fea.ccx_contact.ContactPairDeck`). Prints each rotation's
torques (ours also the part crossing contact) and the frictional torque's relative difference, and that difference
at the stall torque (where the frictionless CalculiX curve carries it; else at the last rotation both reached).
TPU on TPU is far from frictionless, so this bounds the assumption on one candidate. `--axial-thickness-mm`
replaces the study's axial thickness ([geometry] thickness_mm): the in-plane shape stays and the torque grows about
in proportion, so a thicker part carries the stall torque after first contact, where friction can act on it (first
contact moves a little: 3 x 8 mm touches at 0.302 rad 9 mm thick, at 0.282 rad 20 mm thick). The defaults are the
candidate where both CalculiX runs converge (on 6 x 8 mm the node-to-surface pair crawls at first contact, 0.307
rad, frictionless).
"""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
from pathlib import Path

import numpy as np
from record import Table, machine

from seadesign.design.study import load_study
from seadesign.fea.ccx import PathIncrements, path_nodes, run_ccx_path, write_path_inp
from seadesign.fea.ccx_contact import pair_around
from seadesign.fea.rotation_path import PathSettings, path_problem, rotation_path, through_contact
from seadesign.run.cache import Cache
from seadesign.sweep.stages import tetrahedralize

#: ccx's time incrementation for the node-to-surface pair: I0 8, IR 10, IP 9, IC 30 iterations before a cutback,
#: IL 10, IG 4, IS default, IA 10 cutbacks (ccx's defaults 4, 8, 9, 16, 10, 4, 0, 5)
N2F_TIME_CONTROLS = "8,10,9,30,10,4,,10"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--beams", type=int, default=3)
    ap.add_argument("--thickness-mm", type=float, default=8.0)
    ap.add_argument("--axial-thickness-mm", type=float, default=None,
                    help="replace the study's axial thickness (mm; default: the study's)")
    ap.add_argument("--coarsening", type=float, default=4.0)
    ap.add_argument("--max-rotation-rad", type=float, default=0.42)
    ap.add_argument("--friction", type=float, default=0.5)
    ap.add_argument("--reach-mm", type=float, default=1.5, help="the contact pair's faces: within this of where ours touch")
    ap.add_argument("--face-to-face", action="store_true",
                    help="face-to-face pair, ten times our penalty (with friction it does not converge)")
    args = ap.parse_args()
    study = load_study()
    if args.axial_thickness_mm is not None:
        study = dataclasses.replace(study, fixed={**study.fixed, "thickness_mm": args.axial_thickness_mm})
    lc, law = study.load_cases, study.material.law
    checked, part = study.check(study.candidate(beam_count=args.beams, beam_thickness_mm=args.thickness_mm))
    settings = through_contact(PathSettings(max_rotation_rad=args.max_rotation_rad))
    with tempfile.TemporaryDirectory() as d:
        mesh = tetrahedralize(study, checked, part, Cache(Path(d)), coarsening=args.coarsening, layers=1)
        path = rotation_path(mesh, law, lc.impact_torque_Nm, settings)
        if not path.events:
            raise SystemExit(f"the path ends ({path.stop_reason}) before any contact: nothing to compare")
        touch = path_problem(mesh, law, settings).system.contact
        theta = [p.rotation_rad for p in path.points[1:]]
        emesh, hub, ring = path_nodes(mesh)
        runs = {}
        node = not args.face_to_face
        penalty = touch.penalty_Pa_per_m * (1 if node else 10)
        increments = (PathIncrements(max_rad=0.02, residual_rtol=None, time_controls=N2F_TIME_CONTROLS) if node
                      else PathIncrements(max_rad=0.02))
        for mu in (0.0, args.friction):
            deck = pair_around(touch, path.displacement_m, args.reach_mm, penalty, mu, node_to_surface=node)
            inp = write_path_inp(Path(d) / f"friction_{mu:g}.inp", emesh, hub, ring, law, theta, increments, deck)
            runs[mu] = run_ccx_path(inp, emesh.nodes_m, theta)
    free, rough = runs[0.0], runs[args.friction]
    n = min(len(free.torque_Nm), len(rough.torque_Nm))
    change = np.asarray(rough.torque_Nm[:n]) / np.asarray(free.torque_Nm[:n]) - 1  # friction's, relative
    table = Table(["rotation (rad)", "ours, frictionless (Nm)", "ours, through contact (Nm)",
                   "CalculiX, frictionless (Nm)", f"CalculiX, friction {args.friction:g} (Nm)", "friction's change"])
    for i in range(n):
        point = path.points[i + 1]
        table.add(f"{theta[i]:.4f}", f"{point.torque_Nm:.4f}", f"{point.contact.moment_Nm:.4f}",
                  f"{free.torque_Nm[i]:.4f}", f"{rough.torque_Nm[i]:.4f}",
                  f"{change[i]:+.1e}")
    event = path.events[0]
    at = np.flatnonzero(free.torque_Nm[:n] >= lc.stall_torque_Nm)
    i = int(at[0]) if len(at) else n - 1
    where = "the first rotation carrying the stall torque" if len(at) else "the last rotation both reached"
    summary = (f"Friction {args.friction:g} changes the torque by {change[i]:+.1e} "
               f"(relative) at {theta[i]:.4f} rad ({where}; stall torque {lc.stall_torque_Nm:g} Nm), where contact "
               f"carries {path.points[i + 1].contact.moment_Nm:.3g} Nm in our path. First contact at "
               f"{event.rotation_rad:.4f} rad, {event.torque_Nm:.3g} Nm; our path ends: {path.stop_reason} at "
               f"{path.stop_rotation_rad:.4f} rad, {path.stop_torque_Nm:.4g} Nm.")
    settings_text = (f"{args.beams} beams x {args.thickness_mm:g} mm, {part.params.thickness_mm:g} mm thick, "
                     f"path mesh {args.coarsening:g}x coarser "
                     f"({len(mesh.tets)} tetrahedra), to {args.max_rotation_rad:g} rad; "
                     f"{'node-to-surface' if node else 'face-to-face'} contact pair within "
                     f"{args.reach_mm:g} mm of where ours touches; CalculiX {free.wall_s:.0f} s "
                     f"frictionless, {rough.wall_s:.0f} s with friction")
    print(f"machine: {machine()}\n{settings_text}\n{table.markdown()}\n{summary}")
    for name, run in (("frictionless", free), (f"friction {args.friction:g}", rough)):
        if run.failure:
            print(f"CalculiX {name} did not converge past {run.reached_rad:.4f} rad: {run.failure}")


if __name__ == "__main__":
    main()
