"""A contact pair for CalculiX's check of the path through self-contact (`fea.ccx.write_path_inp`): the slave and
master surfaces as element faces, face-to-face penalty contact, optional Coulomb friction, and the surfaces chosen
around where our path's contact presses (the same surfaces, so that the two solvers answer the same question).
SI units (m, Pa); facets are boundary triangles by their corner nodes."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from seadesign.errors import SolverError
from seadesign.fea.contact import FrictionlessContact
from seadesign.fea.contact_geometry import FACE_POINTS, SUBFACETS
from seadesign.fea.torsion import MM

TOUCHING_MM = 0.01  # a pair this close touches (a converged path's pressed pairs penetrate by the tolerance, 0.0045 mm)

#: C3D10's faces S1 to S4 by their corner and midside nodes (0-based within the element; midsides 4 to 9 on the
#: edges 01, 12, 20, 03, 13, 23)
_TET_FACE_NODES = ((0, 1, 2, 4, 5, 6), (0, 3, 1, 7, 8, 4), (1, 3, 2, 8, 9, 5), (2, 3, 0, 9, 7, 6))
_TET_FACES = tuple(face[:3] for face in _TET_FACE_NODES)  # by their corners
#: node-to-surface contact's tension for large clearances (Pa): CalculiX's sigma_infinity, negligible here
_N2F_TENSION_PA = 1.0


def element_faces(elements: np.ndarray, corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The element (0-based) and its face number (1 to 4, C3D10's S1 to S4) of each boundary facet, given by its
    corner nodes (k, 3)."""
    faces = np.sort(elements[:, _TET_FACES], axis=2).reshape(-1, 3)  # (4 m, 3): element-major
    index = {tuple(f): i for i, f in enumerate(faces.tolist())}
    try:
        hits = np.array([index[tuple(f)] for f in np.sort(corners, axis=1).tolist()], dtype=np.int64)
    except KeyError as missing:
        raise SolverError(f"facet {missing} is no element's face") from None
    return hits // 4, hits % 4 + 1


def face_nodes(elements: np.ndarray, facets: np.ndarray) -> np.ndarray:
    """The nodes (0-based, sorted) of boundary facets (k, 3 corner nodes) of a C3D10 mesh: corners and midsides."""
    element, face = element_faces(elements, facets)
    return np.unique(elements[element[:, None], np.array(_TET_FACE_NODES)[face - 1]])


@dataclass(frozen=True)
class ContactPairDeck:
    """A frictional or frictionless contact pair for a CalculiX deck: the slave and master surfaces as boundary
    facets (k, 3 corner nodes, 0-based), penalty contact with a linear pressure-overclosure law of slope
    `penalty_Pa_per_m`; Coulomb friction `friction` (0: frictionless) with stick slope `stick_Pa_per_m`.

    `node_to_surface` False: face-to-face (TYPE=SURFACE TO SURFACE) between the two facet sets. True: node-to-surface,
    the slave the slave facets' nodes (corners and midsides) less any node of a master facet. Where the two sets
    share an edge (a notch's root folding shut: the pair is a face and its neighbour), face-to-face pairs the slave
    face's integration points at that edge with the master face across it, a contact element whose slave and master
    are the same nodes; frictionless it is harmless, with friction its stick/slip never settles (CalculiX cut to
    1.6e-4 rad and stopped at 0.261 rad on the 3 x 8 mm candidate, before any real contact). Node-to-surface leaves
    the shared nodes out of the slave."""

    slave: np.ndarray
    master: np.ndarray
    penalty_Pa_per_m: float
    friction: float = 0.0
    stick_Pa_per_m: float = 0.0
    node_to_surface: bool = False

    def card(self, elements: np.ndarray) -> str:
        """The *SURFACE, *SURFACE INTERACTION and *CONTACT PAIR cards (model data)."""
        lines = []
        if self.node_to_surface:
            nodes = np.setdiff1d(face_nodes(elements, self.slave), face_nodes(elements, self.master))
            if not len(nodes):
                raise SolverError("every slave node is on the master surface: no node-to-surface pair")
            lines.append("*SURFACE, NAME=SLAVE, TYPE=NODE")
            lines += [f"{n + 1}" for n in nodes]
        sides = (("MASTER", self.master),) if self.node_to_surface else (("SLAVE", self.slave), ("MASTER", self.master))
        for name, facets in sides:
            element, face = element_faces(elements, facets)
            lines.append(f"*SURFACE, NAME={name}, TYPE=ELEMENT")
            lines += [f"{e + 1}, S{k}" for e, k in zip(element, face)]
        behavior = f"{self.penalty_Pa_per_m:.6e}" + (f", {_N2F_TENSION_PA:.6e}" if self.node_to_surface else "")
        lines += ["*SURFACE INTERACTION, NAME=TOUCH", "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR", behavior]
        if self.friction > 0:
            lines += ["*FRICTION", f"{self.friction:.6e}, {self.stick_Pa_per_m:.6e}"]
        kind = "NODE TO SURFACE" if self.node_to_surface else "SURFACE TO SURFACE"
        lines += [f"*CONTACT PAIR, INTERACTION=TOUCH, TYPE={kind}", "SLAVE, MASTER"]
        return "\n".join(lines) + "\n"


def pair_around(contact: FrictionlessContact, u: np.ndarray, reach_mm: float, penalty_Pa_per_m: float,
                friction: float = 0.0, node_to_surface: bool = False) -> ContactPairDeck:
    """The slave and master surfaces around the pairs that touch at u (our path's solution; gap below `TOUCHING_MM`):
    the faces of `contact`'s surface within `reach_mm` of a touching pair's face at rest, each given to the side of
    the nearest pair whose face it turns like (the checked point's face: slave; the facet's face: master), a face
    turned like neither (cosine 0.3 or less) to none. `friction`: Coulomb's coefficient, with the stick slope the
    penalty's. `node_to_surface`: as `ContactPairDeck`'s."""
    pairs = contact.pairs(u, contact.search(u))
    touching = pairs.gap_m < TOUCHING_MM * MM
    if not touching.any():
        raise SolverError("no surfaces touch at this state: there is no pair to check")
    corners = contact.surface.faces[:, :3]
    x = contact.surface.nodes_m[corners] / MM
    centroids = x.mean(axis=1)
    normals = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    slave, master = pairs.point[touching] // len(FACE_POINTS), pairs.facet[touching] // len(SUBFACETS)
    seeds = np.concatenate([slave, master])
    distance = np.linalg.norm(centroids[:, None] - centroids[seeds][None], axis=2)
    nearest = np.argmin(distance, axis=1) % len(slave)
    near = distance.min(axis=1) <= reach_mm
    like_slave = np.einsum("ki,ki->k", normals, normals[slave][nearest])
    like_master = np.einsum("ki,ki->k", normals, normals[master][nearest])
    on_slave = near & (like_slave > 0.3) & (like_slave > like_master)
    on_master = near & (like_master > 0.3) & (like_master > like_slave)
    return ContactPairDeck(corners[on_slave], corners[on_master], penalty_Pa_per_m, friction,
                           penalty_Pa_per_m if friction > 0 else 0.0, node_to_surface)
