"""CalculiX (ccx) as an independent solver on the same mesh: input writers, runners, .dat parser.

Decks are in SI units (m, N, Pa): C3D10 elements in the same node order as ours, node sets HUB
and RING for the coupled surfaces.
- Linear torsion (`write_inp`): the hub tied to a reference point by *RIGID BODY (kinematically
  rigid, like an RBE2), the ring held, and a moment about +z on the rigid body's rotation node.
- The large-deflection path (`write_path_inp`), the check of `fea.rotation_path`: *HYPERELASTIC
  with the law's constants, one *STEP, NLGEOM per requested rotation theta, each hub node driven
  to x' = R(theta) x about z (no translation, no tilt, as the servo holds it), the ring held;
  the reaction torque is read from the hub nodes' reaction forces.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence, TextIO

import numpy as np

from seadesign.design.materials import Hyperelastic
from seadesign.errors import SolverError
from seadesign.fea.ccx_contact import ContactPairDeck
from seadesign.fea.elements import ElementMesh, element_mesh
from seadesign.fea.hub_rotation import HubRotation, moment_z
from seadesign.fea.torsion import MM, UnitTorsion
from seadesign.mesh.tetmesh import TetMesh


def _block(ids: np.ndarray, per_line: int = 16) -> str:
    ids = np.asarray(ids) + 1
    return "\n".join(", ".join(map(str, ids[i : i + per_line])) for i in range(0, len(ids), per_line))


def _write_mesh(f: TextIO, emesh: ElementMesh, hub_nodes: np.ndarray, ring_nodes: np.ndarray) -> None:
    """Nodes (set NALL), C3D10 elements (set EALL) and the node sets HUB and RING, numbered ours + 1."""
    if emesh.order != 2:
        raise SolverError("the CalculiX export writes C3D10 elements; build the mesh with order 2")
    f.write("*NODE, NSET=NALL\n")
    np.savetxt(f, np.column_stack([np.arange(1, len(emesh.nodes_m) + 1), emesh.nodes_m]),
               fmt=["%d", "%.12e", "%.12e", "%.12e"], delimiter=", ")
    f.write("*ELEMENT, TYPE=C3D10, ELSET=EALL\n")
    np.savetxt(f, np.column_stack([np.arange(1, len(emesh.elements) + 1), emesh.elements + 1]), fmt="%d", delimiter=", ")
    f.write(f"*NSET, NSET=HUB\n{_block(hub_nodes)}\n")
    f.write(f"*NSET, NSET=RING\n{_block(ring_nodes)}\n")


def write_inp(
    path: Path,
    emesh: ElementMesh,
    hub_nodes: np.ndarray,
    ring_nodes: np.ndarray,
    ref_m: np.ndarray,
    youngs_modulus_Pa: float,
    poisson_ratio: float,
    torque_Nm: float,
    loaded: str = "hub",
) -> Path:
    """Write a CalculiX deck: torque_Nm about +z on the rigidly coupled `loaded` side ("hub":
    stall case, "ring": impact case), the other side's surface held.

    Node and element numbers are ours + 1; the two extra nodes N+1 (reference) and N+2 (rotation)
    carry the rigid body's translation and rotation (its dofs 1-3 are rotations about x, y, z).
    """
    if loaded not in ("hub", "ring"):
        raise SolverError(f"loaded side must be 'hub' or 'ring', got {loaded!r}")
    coupled, held = ("HUB", "RING") if loaded == "hub" else ("RING", "HUB")
    n = len(emesh.nodes_m)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    ref = ", ".join(f"{c:.12e}" for c in ref_m)
    with open(path, "w") as f:
        f.write(f"*HEADING\nseadesign torsion: {coupled} rigid with a moment about +z, {held} held; units m, N, Pa\n")
        _write_mesh(f, emesh, hub_nodes, ring_nodes)
        f.write(f"*NODE, NSET=REFNODES\n{n + 1}, {ref}\n{n + 2}, {ref}\n")
        f.write(f"*MATERIAL, NAME=SPRING\n*ELASTIC\n{youngs_modulus_Pa:.12e}, {poisson_ratio:.12e}\n")
        f.write("*SOLID SECTION, ELSET=EALL, MATERIAL=SPRING\n")
        f.write(f"*RIGID BODY, NSET={coupled}, REF NODE={n + 1}, ROT NODE={n + 2}\n")
        f.write(f"*BOUNDARY\n{held}, 1, 3\n")
        f.write("*STEP\n*STATIC\n")
        f.write(f"*CLOAD\n{n + 2}, 3, {torque_Nm:.12e}\n")
        f.write("*NODE PRINT, NSET=NALL\nU\n")
        f.write("*NODE PRINT, NSET=REFNODES\nU\n")
        f.write(f"*NODE PRINT, NSET={held}\nRF\n")
        f.write("*END STEP\n")
    return path


@dataclass(frozen=True)
class CcxResult:
    """CalculiX results: displacements (N, 3) in m, rotation of the loaded side about z (rad),
    reaction forces (N) on the held nodes (0-based ids), wall time (s) of the ccx run."""

    displacement_m: np.ndarray
    rotation_rad: float
    held_nodes: np.ndarray
    reaction_N: np.ndarray
    wall_s: float


def _dat_sections(text: str) -> list[tuple[str, list[list[float]]]]:
    """Each text header of a .dat file with the numeric rows after it, in file order."""
    sections: list[tuple[str, list[list[float]]]] = []
    for line in text.splitlines():
        s = line.strip()
        if not s:
            continue
        if s[0].isalpha():
            sections.append((s, []))
        elif sections:
            sections[-1][1].append([float(v) for v in s.replace("D", "E").split()])
    return sections


def _dat_blocks(text: str) -> dict[str, list[list[float]]]:
    """Numeric rows after each text header of a .dat file, keyed by the header."""
    return dict(_dat_sections(text))


def _run(inp: Path, timeout_s: float, threads: int | None) -> tuple[subprocess.CompletedProcess, float]:
    """Run ccx on a deck (needs `ccx` on PATH) with `threads` threads (default: all cores): the
    finished process and its wall time (s)."""
    exe = shutil.which("ccx")
    if exe is None:
        raise SolverError("CalculiX `ccx` is not on PATH; install it (Debian: apt-get install calculix-ccx)")
    env = dict(os.environ)
    nproc = str(threads or os.cpu_count() or 1)
    env.update(OMP_NUM_THREADS=nproc, CCX_NPROC_EQUATION_SOLVER=nproc)
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(
            [exe, "-i", inp.stem], cwd=inp.parent, env=env, capture_output=True, text=True, timeout=timeout_s
        )
    except subprocess.TimeoutExpired:
        raise SolverError(f"ccx did not finish within {timeout_s} s; raise timeout_s or coarsen the mesh") from None
    return proc, time.perf_counter() - t0


def _tail(proc: subprocess.CompletedProcess, lines: int = 15) -> str:
    return "\n".join((proc.stdout + proc.stderr).splitlines()[-lines:])


def run_ccx(inp: Path, n_nodes: int, timeout_s: float = 600.0, threads: int | None = None) -> CcxResult:
    """Run ccx on a deck from write_inp and parse its .dat (needs `ccx` on PATH)."""
    inp = Path(inp)
    proc, wall = _run(inp, timeout_s, threads)
    dat = inp.with_suffix(".dat")
    if proc.returncode != 0 or not dat.exists() or "ERROR" in proc.stdout:
        raise SolverError(f"ccx failed (exit {proc.returncode}):\n{_tail(proc)}")
    blocks = _dat_blocks(dat.read_text())
    disp = np.array(next(v for k, v in blocks.items() if k.startswith("displacements") and "NALL" in k))
    ref = {int(r[0]): r[1:4] for r in next(v for k, v in blocks.items() if k.startswith("displacements") and "REFNODES" in k)}
    rf = np.array(next(v for k, v in blocks.items() if k.startswith("forces")))
    u = np.zeros((n_nodes, 3))
    u[disp[:, 0].astype(int) - 1] = disp[:, 1:4]
    return CcxResult(
        displacement_m=u,
        rotation_rad=float(ref[n_nodes + 2][2]),
        held_nodes=rf[:, 0].astype(int) - 1,
        reaction_N=rf[:, 1:4],
        wall_s=wall,
    )


def write_load_case_decks(
    directory: Path,
    unit: UnitTorsion,
    youngs_modulus_Pa: float,
    poisson_ratio: float,
    stall_torque_Nm: float,
    impact_torque_Nm: float,
) -> dict[str, Path]:
    """stall.inp (torque on the hub, ring held) and impact.inp (torque on the ring, hub held)
    for the mesh and couplings of a solve, so anyone can rerun them with `ccx -i stall`."""
    hub = np.unique(np.concatenate(list(unit.hub_groups.values())))
    directory = Path(directory)
    return {
        case: write_inp(
            directory / f"{case}.inp", unit.emesh, hub, unit.ring_nodes, unit.ref_m,
            youngs_modulus_Pa, poisson_ratio, torque, loaded=side,
        )
        for case, torque, side in (("stall", stall_torque_Nm, "hub"), ("impact", impact_torque_Nm, "ring"))
    }


def path_nodes(mesh: TetMesh, hub_boundaries: list[str] | None = None,
               ring_boundaries: list[str] | None = None) -> tuple[ElementMesh, np.ndarray, np.ndarray]:
    """The P2 element mesh (m) and the driven hub and held ring nodes (0-based) of `rotation_path` on `mesh`
    with these boundaries, from the path's own boundary condition, so that a deck drives and holds the
    same nodes."""
    emesh = element_mesh(mesh.points_mm * MM, mesh.tets, 2)
    drive = HubRotation.on(mesh, emesh, hub_boundaries, ring_boundaries)
    return emesh, drive.hub, drive.ring


_NEVER = 10**9  # a print frequency no step reaches: ccx then prints each step's last increment only


@dataclass(frozen=True)
class PathIncrements:
    """Automatic incrementation of each NLGEOM step in rad of hub rotation (a step's time is its
    rotation): each step starts with its whole rotation, at most `max_rad`, and ccx cuts back down to
    `min_rad`; `residual_rtol` is ccx's convergence criterion, its largest residual force over its
    average nodal force (ccx's default, 0.005, left torque errors of 1.2e-6 on the test annulus; 1e-7
    leaves only the .dat's printed digits, 6e-8, for one more iteration in six); None leaves ccx's field defaults
    (no *CONTROLS, PARAMETERS=FIELD). `time_controls`: a *CONTROLS, PARAMETERS=TIME INCREMENTATION line (I0, IR, IP,
    IC, IL, IG, IS, IA) in every step, None for ccx's defaults (4, 8, 9, 16, 10, 4, 0, 5)."""

    max_rad: float = 0.1
    min_rad: float = 1e-6
    residual_rtol: float | None = 1e-7
    time_controls: str | None = None


#: a compressibility that leaves its volumetric term out of CalculiX's energy (1/Pa)
ABSENT_D_PER_PA = 1e30


def hyperelastic_card(law: Hyperelastic) -> str:
    """The *HYPERELASTIC card of `law` in CalculiX's constants (moduli Pa, compressibilities 1/Pa): NEO HOOKE
    (C10, D1), MOONEY-RIVLIN (C10, C01, D1) or YEOH (C10, C20, C30, D1, D2, D3). A term our law leaves out (D2 or
    D3 = 0) is written as D = 1e30 1/Pa, which leaves it out to double precision: CalculiX does not read D = 0 as
    absent (measured: a Yeoh law with C20 = 0 and D2 = D3 = 0 gave 32 % more torque than the same neo-Hookean law)."""
    def d(value: float) -> float:
        return value if value > 0 else ABSENT_D_PER_PA

    rows = {"neo_hooke": ("NEO HOOKE", (law.c10_Pa, law.d1_per_Pa)),
            "mooney_rivlin": ("MOONEY-RIVLIN", (law.c10_Pa, law.c01_Pa, law.d1_per_Pa)),
            "yeoh": ("YEOH", (law.c10_Pa, law.c20_Pa, law.c30_Pa, law.d1_per_Pa, d(law.d2_per_Pa), d(law.d3_per_Pa)))}
    if law.model not in rows:
        raise SolverError(f"the NLGEOM export writes neo_hooke, mooney_rivlin or yeoh laws; the law is {law.model!r}")
    name, constants = rows[law.model]
    return f"*HYPERELASTIC, {name}\n" + ", ".join(f"{c:.12e}" for c in constants) + "\n"


def write_path_inp(
    path: Path,
    emesh: ElementMesh,
    hub_nodes: np.ndarray,
    ring_nodes: np.ndarray,
    law: Hyperelastic,
    rotations_rad: Sequence[float],
    increments: PathIncrements = PathIncrements(),
    contact: ContactPairDeck | None = None,
) -> Path:
    """Write a CalculiX NLGEOM deck of the rotation path: the hyperelastic law (`hyperelastic_card`;
    C3D10 integrates it at every point, as the path's formulation "full"), the ring nodes held, the hub
    nodes' u_z = 0, and one *STEP, NLGEOM per rotation (rad, increasing) that ends with every hub node
    at x' = R(theta) x about z (within a step the displacements ramp linearly: only step ends are
    read). Each step prints the hub nodes' displacements and reaction forces at its end only. `contact`: a contact
    pair between two sets of the part's boundary facets (the check of the path through self-contact)."""
    card = hyperelastic_card(law)
    theta = np.asarray(rotations_rad, dtype=float)
    if theta.ndim != 1 or not len(theta) or theta[0] <= 0 or np.any(np.diff(theta) <= 0):
        raise SolverError(f"rotations_rad must be positive and increasing, got {theta}")
    hub = np.asarray(hub_nodes)
    x, y = emesh.nodes_m[hub, 0], emesh.nodes_m[hub, 1]
    ids, dofs = np.repeat(hub + 1, 2), np.tile([1, 2], len(hub))
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w") as f:
        f.write("*HEADING\nseadesign rotation path: HUB turned about +z (x' = R(theta) x), RING held; NLGEOM; "
                "units m, N, Pa\n")
        _write_mesh(f, emesh, hub, ring_nodes)
        f.write(f"*MATERIAL, NAME=SPRING\n{card}")
        f.write("*SOLID SECTION, ELSET=EALL, MATERIAL=SPRING\n*BOUNDARY\nRING, 1, 3\nHUB, 3, 3\n")
        if contact is not None:
            f.write(contact.card(emesh.elements))
        for before, t in zip(np.concatenate([[0.0], theta[:-1]]), theta):
            c, s = np.cos(t), np.sin(t)
            u = np.column_stack([(c - 1) * x - s * y, s * x + (c - 1) * y]).ravel()
            span = t - before
            first, rtol = min(increments.max_rad, span), increments.residual_rtol
            f.write(f"*STEP, NLGEOM, INC={int(np.ceil(span / increments.min_rad)) + 1}\n*STATIC\n"
                    f"{first:.12e}, {span:.12e}, {increments.min_rad:.12e}, {first:.12e}\n")
            if rtol is not None:
                f.write(f"*CONTROLS, PARAMETERS=FIELD\n{rtol:.3e}, , , , {rtol:.3e}\n")
            if increments.time_controls is not None:
                f.write(f"*CONTROLS, PARAMETERS=TIME INCREMENTATION\n{increments.time_controls}\n")
            f.write("*BOUNDARY\n")
            np.savetxt(f, np.column_stack([ids, dofs, dofs, u]), fmt=["%d", "%d", "%d", "%.12e"], delimiter=", ")
            f.write(f"*NODE PRINT, NSET=HUB, FREQUENCY={_NEVER}\nU, RF\n*END STEP\n")
    return path


@dataclass(frozen=True)
class CcxPath:
    """CalculiX's torque-rotation path: the requested rotations (rad) whose steps converged, in order,
    and the reaction torque about z (Nm) there; `failure` is ccx's message when a step did not
    converge (that rotation and the later ones are absent), None when all did; `reached_rad` is the
    rotation of the last increment ccx converged (within a step it did not finish, where it stopped).
    Increments and Newton iterations count every attempt (cut-back ones too); wall time in s."""

    rotation_rad: np.ndarray
    torque_Nm: np.ndarray
    failure: str | None
    reached_rad: float
    increments: int
    iterations: int
    wall_s: float


def run_ccx_path(inp: Path, nodes_m: np.ndarray, rotations_rad: Sequence[float], timeout_s: float = 3600.0,
                 threads: int | None = None) -> CcxPath:
    """Run a deck from write_path_inp (the same rotations; `nodes_m` the mesh's nodes, m) and read the
    torque of each converged step: sum over the hub nodes of (x + u) x RF, z component, as the path's
    `HubRotation.torque`. Steps ccx did not converge are left out and named in `failure`."""
    inp = Path(inp)
    theta = np.asarray(rotations_rad, dtype=float)
    proc, wall = _run(inp, timeout_s, threads)
    dat, sta, cvg = (inp.with_suffix(e) for e in (".dat", ".sta", ".cvg"))
    errors = [line.strip() for line in proc.stdout.splitlines() if "ERROR" in line]
    if not dat.exists() or not sta.exists() or (proc.returncode != 0 and not errors):
        raise SolverError(f"ccx failed (exit {proc.returncode}) before any step:\n{_tail(proc)}")
    sections = _dat_sections(dat.read_text())
    disp = [(k, v) for k, v in sections if k.startswith("displacements")]
    forces = [v for k, v in sections if k.startswith("forces")]
    printed = np.array([float(k.rsplit(maxsplit=1)[1]) for k, _ in disp])
    n = len(printed)
    if n > len(theta) or not np.allclose(printed, theta[:n], rtol=1e-6, atol=0.0):
        raise SolverError(f"ccx printed steps at {printed} rad, not the requested {theta}; "
                          "was the deck written by write_path_inp with these rotations?")
    if (n < len(theta)) != bool(errors):
        raise SolverError(f"ccx converged {n} of {len(theta)} steps, exit {proc.returncode}:\n{_tail(proc)}")
    torque = []
    for (_, u), f in zip(disp, forces):
        u, f = np.array(u), np.array(f)
        if not np.array_equal(u[:, 0], f[:, 0]):
            raise SolverError("ccx printed displacements and reaction forces of different hub nodes")
        torque.append(moment_z(nodes_m[u[:, 0].astype(int) - 1] + u[:, 1:4], f[:, 1:4]))
    increments = [line.split() for line in sta.read_text().splitlines()[2:]]
    converged = [float(row[4]) for row in increments if not row[2].endswith("U")]  # attempts that failed read "1U"
    return CcxPath(
        rotation_rad=theta[:n],
        torque_Nm=np.array(torque),
        failure=f"{'; '.join(errors)} (step to {theta[n]:.6g} rad)" if errors else None,
        reached_rad=max(converged, default=0.0),
        increments=len(increments),
        iterations=sum(1 for line in cvg.read_text().splitlines()[4:] if line.split()),
        wall_s=wall,
    )
