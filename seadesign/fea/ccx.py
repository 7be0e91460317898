"""CalculiX (ccx) as an independent solver on the same mesh: input writer, runner, .dat parser.

The deck is in SI units (m, N, Pa): C3D10 elements in the same node order as ours, node sets
HUB and RING for the coupled surfaces, the hub tied to a reference point by *RIGID BODY
(kinematically rigid, like an RBE2), the ring held, and a unit-scaled moment about +z on the
rigid body's rotation node.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from seadesign.errors import SolverError
from seadesign.fea.elements import ElementMesh
from seadesign.fea.torsion import UnitTorsion


def _block(ids: np.ndarray, per_line: int = 16) -> str:
    ids = np.asarray(ids) + 1
    return "\n".join(", ".join(map(str, ids[i : i + per_line])) for i in range(0, len(ids), per_line))


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
    if emesh.order != 2:
        raise SolverError("the CalculiX export writes C3D10 elements; build the mesh with order 2")
    if loaded not in ("hub", "ring"):
        raise SolverError(f"loaded side must be 'hub' or 'ring', got {loaded!r}")
    coupled, held = ("HUB", "RING") if loaded == "hub" else ("RING", "HUB")
    n = len(emesh.nodes_m)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    nodes = np.column_stack([np.arange(1, n + 1), emesh.nodes_m])
    elems = np.column_stack([np.arange(1, len(emesh.elements) + 1), emesh.elements + 1])
    ref = ", ".join(f"{c:.12e}" for c in ref_m)
    with open(path, "w") as f:
        f.write(f"*HEADING\nseadesign torsion: {coupled} rigid with a moment about +z, {held} held; units m, N, Pa\n")
        f.write("*NODE, NSET=NALL\n")
        np.savetxt(f, nodes, fmt=["%d", "%.12e", "%.12e", "%.12e"], delimiter=", ")
        f.write(f"*NODE, NSET=REFNODES\n{n + 1}, {ref}\n{n + 2}, {ref}\n")
        f.write("*ELEMENT, TYPE=C3D10, ELSET=EALL\n")
        np.savetxt(f, elems, fmt="%d", delimiter=", ")
        f.write(f"*NSET, NSET=HUB\n{_block(hub_nodes)}\n")
        f.write(f"*NSET, NSET=RING\n{_block(ring_nodes)}\n")
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


def _dat_blocks(text: str) -> dict[str, list[list[float]]]:
    """Numeric rows after each text header of a .dat file, keyed by the header."""
    blocks: dict[str, list[list[float]]] = {}
    current = None
    for line in text.splitlines():
        s = line.strip()
        if not s:
            continue
        if s[0].isalpha():
            current = s
            blocks[current] = []
        elif current is not None:
            blocks[current].append([float(v) for v in s.replace("D", "E").split()])
    return blocks


def run_ccx(inp: Path, n_nodes: int, timeout_s: float = 600.0, threads: int | None = None) -> CcxResult:
    """Run ccx on a deck from write_inp and parse its .dat (needs `ccx` on PATH)."""
    exe = shutil.which("ccx")
    if exe is None:
        raise SolverError("CalculiX `ccx` is not on PATH; install it (Debian: apt-get install calculix-ccx)")
    inp = Path(inp)
    env = dict(os.environ)
    nproc = str(threads or os.cpu_count() or 1)
    env.update(OMP_NUM_THREADS=nproc, CCX_NPROC_EQUATION_SOLVER=nproc)
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(
            [exe, "-i", inp.stem], cwd=inp.parent, env=env, capture_output=True, text=True, timeout=timeout_s
        )
    except subprocess.TimeoutExpired:
        raise SolverError(f"ccx did not finish within {timeout_s} s") from None
    wall = time.perf_counter() - t0
    dat = inp.with_suffix(".dat")
    if proc.returncode != 0 or not dat.exists() or "ERROR" in proc.stdout:
        tail = "\n".join((proc.stdout + proc.stderr).splitlines()[-15:])
        raise SolverError(f"ccx failed (exit {proc.returncode}):\n{tail}")
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
