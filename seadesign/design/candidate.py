"""Build and check every candidate of a study: the geometry stage of the sweep."""

from __future__ import annotations

from dataclasses import dataclass

from seadesign.errors import ConfigError
from seadesign.design.geometry import Part, build_part
from seadesign.design.params import GeometryParams
from seadesign.design.study import Study
from seadesign.design.validity import check


@dataclass
class CheckedPart:
    """A built candidate with its validity verdict, volume (mm^3) and mass (kg)."""

    part: Part
    reasons: list[str]
    mass_kg: float

    @property
    def valid(self) -> bool:
        return not self.reasons

    @property
    def params(self) -> GeometryParams:
        return self.part.params


def check_candidate(study: Study, params: GeometryParams) -> CheckedPart:
    """Build one candidate and run the validity checks."""
    part = build_part(params)
    reasons = check(part, study.validity)
    mass = part.volume_mm3 * 1e-9 * study.material.density_kg_per_m3
    return CheckedPart(part, reasons, mass)


def find_candidate(study: Study, beam_count: int, beam_thickness_mm: float) -> GeometryParams:
    """The study's candidate with these parameters (must be in its design space)."""
    if beam_count not in study.beam_counts or beam_thickness_mm not in study.beam_thicknesses_mm:
        raise ConfigError(
            f"--beams {beam_count} --thickness-mm {beam_thickness_mm:g} is not in study '{study.name}' "
            f"(beam counts {list(study.beam_counts)}, thicknesses {list(study.beam_thicknesses_mm)} mm)"
        )
    return study.params(beam_count, beam_thickness_mm)
