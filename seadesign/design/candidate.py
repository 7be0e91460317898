"""The candidate: one point of a study's design space, and its checked geometry.

A `Candidate` carries the design-axis values that name it and the full geometry they give. Once
checked (`check_candidate`, or `with_geometry` from a cached verdict) it also carries its validity
reasons, volume (mm^3) and mass (kg). The CadQuery `Part` is returned beside it, not inside: it
is needed only to mesh and export, and it does not pickle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from seadesign.design.materials import Material
from seadesign.design.params import GeometryParams, ValidityRules
from seadesign.design.space import Value, candidate_name, file_stem

if TYPE_CHECKING:
    from seadesign.design.geometry import Part


@dataclass(frozen=True)
class Candidate:
    """Design-axis values (key, value) in the study's axis order, the geometry and material they
    give, and, once checked, the validity reasons (empty: valid), volume (mm^3) and mass (kg)."""

    values: tuple[tuple[str, Value], ...]
    params: GeometryParams
    material: Material
    reasons: tuple[str, ...] | None = None  # None: not checked yet
    volume_mm3: float = math.nan
    mass_kg: float = math.nan

    @property
    def name(self) -> str:
        """E.g. "4 beams x 8 mm" (see `space.label`)."""
        return candidate_name(self.values)

    @property
    def stem(self) -> str:
        """File-name stem of the candidate's exports, e.g. "4beams_8mm"."""
        return file_stem(self.name)

    @property
    def checked(self) -> bool:
        """Whether the validity checks have run (`Study.check`)."""
        return self.reasons is not None

    @property
    def valid(self) -> bool:
        """Whether the checked candidate passed every validity check; ValueError before it is checked."""
        if self.reasons is None:
            raise ValueError(f"candidate {self.name} has not been checked yet")
        return not self.reasons

    def with_geometry(self, reasons: tuple[str, ...], volume_mm3: float) -> "Candidate":
        """This candidate checked: its validity reasons, volume and mass (from its material's density).

        Parameters
        ----------
        reasons : tuple of str
            Why the candidate is invalid; empty: valid.
        volume_mm3 : float
            The solid's volume (mm^3).

        Returns
        -------
        Candidate
            A copy with ``reasons``, ``volume_mm3`` and ``mass_kg`` (kg) set.

        Examples
        --------
        >>> import seadesign as sd
        >>> cand = sd.load_study("wolfgang_knee").candidate(beam_count=6, beam_thickness_mm=8.0)
        >>> round(cand.with_geometry((), 22000.0).mass_kg, 4)
        0.0262
        """
        return replace(self, reasons=tuple(reasons), volume_mm3=float(volume_mm3),
                       mass_kg=float(volume_mm3) * 1e-9 * self.material.density_kg_per_m3)


def check_candidate(candidate: Candidate, rules: ValidityRules) -> tuple[Candidate, Part]:
    """Build the candidate's solid and run the validity checks: (checked candidate, CAD part)."""
    from seadesign.design.geometry import build_part
    from seadesign.design.validity import check

    part = build_part(candidate.params)
    return candidate.with_geometry(tuple(check(part, rules)), part.volume_mm3), part
