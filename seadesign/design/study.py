"""Study files (`studies/*.toml`, packaged with seadesign; see `inputs.py`): the design space, fixed geometry,
material, load cases, robot/actuator data, mesh and ranking settings of one design problem.

`[design_space]` names the axes (any numeric geometry key, see `space.py`), `[geometry]` the fixed
values; each candidate's merged geometry is checked when the study loads.

Every key is validated (present, typed, in range, no unknown keys); derived quantities such
as the impact torque are computed here from physical inputs, never typed in.
"""

from __future__ import annotations

import math
import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from seadesign.design.candidate import Candidate, check_candidate
from seadesign.design.inputs import MATERIAL, STUDY, InputFile, StudyFiles
from seadesign.design.materials import Material, load_material_file
from seadesign.design.params import ValidityRules, read_geometry
from seadesign.design.robot import Actuator, LoadCases, Robot, read_actuator, read_load_cases, read_robot
from seadesign.design.requirements import KWindow, Requirements, check_window, k_window, read_requirements, refuse_moved_keys
from seadesign.design.space import MATERIAL_KEY, Axis, Value, grid, merged, read_axes
from seadesign.design.tomlcheck import Table, read_toml
from seadesign.errors import ConfigError

if TYPE_CHECKING:
    from seadesign.design.geometry import Part

DEFAULT_STUDY = STUDY.packaged / "wolfgang_knee.toml"


@dataclass(frozen=True)
class MeshSettings:
    elements_across_beam: float  # target tetrahedra across the beam width
    backend: str  # "pytetwild" or "gmsh"
    elements_per_circle: float = 0.0  # gmsh: curved surfaces (bolt holes, fillets) get this many elements per turn
    layers: float = 0.0  # gmsh, prismatic parts: layers through the thickness (0: about one per element size)

    def scaled(self, refinement: float) -> "MeshSettings":
        """These settings at `refinement` times the density (layers rounded up)."""
        return MeshSettings(self.elements_across_beam * refinement, self.backend,
                            self.elements_per_circle * refinement, math.ceil(self.layers * refinement - 1e-9))

    def mesh_part_options(self) -> dict:
        """Keyword arguments of seadesign.mesh.mesh_part."""
        return {"elements_across_beam": self.elements_across_beam, "elements_per_circle": self.elements_per_circle,
                "layers": math.ceil(self.layers - 1e-9), "backend": self.backend}


@dataclass(frozen=True)
class Ranking:
    """The physical settings a sweep judges candidates with (the constraints and objectives are `Requirements`)."""

    safety_factor: float  # the single-event allowable strain is the elongation at yield / safety_factor
    impact_speed_m_per_s: float  # foot speed at touchdown
    knee_inertia_kg_m2: float  # inertia of the link behind the spring, about the knee


@dataclass(frozen=True)
class Study:
    name: str
    description: str
    path: Path
    materials: dict[str, Material]  # by file stem: the fixed material, or every value of a material axis
    axes: tuple[Axis, ...]  # the design space; every other geometry key is fixed
    fixed: dict  # the raw [geometry] table (nested, mm / deg), without the axes
    validity: ValidityRules
    load_cases: LoadCases
    robot: Robot
    actuator: Actuator
    mesh: MeshSettings
    ranking: Ranking
    bearing_radius_mm: float  # where the stall displacement is read (thesis eq. 5.3)
    requirements: Requirements
    files: StudyFiles  # the study and material files read, with their hashes

    @property
    def strike_speed_rad_per_s(self) -> float:
        """The lower leg's angular speed about the knee at touchdown (rad/s): foot speed / lower leg."""
        return self.ranking.impact_speed_m_per_s / self.robot.lower_leg_m

    @property
    def k_window(self) -> KWindow:
        """The stiffness window the requirements imply on the study's own numbers (`design.requirements`)."""
        return k_window(self.requirements, standing_torque_Nm=self.robot.standing_knee_torque_Nm,
                        stall_torque_Nm=self.load_cases.stall_torque_Nm, lower_leg_m=self.robot.lower_leg_m,
                        knee_inertia_kg_m2=self.ranking.knee_inertia_kg_m2,
                        strike_speed_rad_per_s=self.strike_speed_rad_per_s)

    @property
    def material(self) -> Material:
        """The study's one material (a study whose material is a design axis has none)."""
        if len(self.materials) != 1 or any(a.key == MATERIAL_KEY for a in self.axes):
            raise ConfigError(f"study '{self.name}' has the material as a design axis; ask its candidates")
        return next(iter(self.materials.values()))

    def with_materials(self, materials: dict[str, Material]) -> "Study":
        """The same study with other material data under the same names (e.g. a calibrated modulus).

        Parameters
        ----------
        materials : dict of str to Material
            Material key -> the material data to use under that key.

        Returns
        -------
        Study
            A copy; this study is unchanged.

        Examples
        --------
        >>> import seadesign as sd
        >>> study = sd.load_study("wolfgang_knee")
        >>> soft = study.with_materials({"ninjaflex": study.material.scaled(0.5, "bench test")})
        """
        return dataclasses.replace(self, materials={**self.materials, **materials})

    def candidates(self) -> list[Candidate]:
        """Every combination of the discrete axes' values, the first axis varying fastest.

        Returns
        -------
        list of Candidate
            Unchecked candidates (see `check`).

        Raises
        ------
        ConfigError
            A design axis is continuous (an explorer study): it has no grid.

        Examples
        --------
        >>> import seadesign as sd
        >>> [c.name for c in sd.load_study("wolfgang_knee").candidates()][:2]
        ['3 beams x 4 mm', '4 beams x 4 mm']
        """
        return [self._candidate(values) for values in grid(self.axes)]

    def candidate(self, *values: Value, **by_key: Value) -> Candidate:
        """The candidate with these axis values, in axis order or by key (dotted keys by `**{}`).

        Parameters
        ----------
        *values : float, int or str
            Axis values in the study's axis order (lengths in mm, as the axis key says).
        **by_key : float, int or str
            Axis values by key, e.g. ``beam_count=6, beam_thickness_mm=8.0``.

        Returns
        -------
        Candidate
            Unchecked (see `check`).

        Raises
        ------
        ConfigError
            An axis is missing, unknown, or its value is outside the study's design space; the message names the
            axes and their values.

        Examples
        --------
        >>> import seadesign as sd
        >>> sd.load_study("wolfgang_knee").candidate(beam_count=6, beam_thickness_mm=8.0).name
        '6 beams x 8 mm'
        """
        keys = [a.key for a in self.axes]
        if len(values) > len(keys) or set(by_key) - set(keys):
            raise ConfigError(f"study '{self.name}' has the design axes {keys}; got values {list(values)} "
                              f"and keys {sorted(by_key)}")
        given = dict(zip(keys, values), **by_key)
        axes_text = "; ".join(a.describe() for a in self.axes)
        for axis in self.axes:
            value = given.get(axis.key)
            if value is None or not axis.contains(value):
                shown = "(missing)" if value is None else value if isinstance(value, str) else f"{value:g}"
                raise ConfigError(f"{axis.key} = {shown} is not in study '{self.name}' ({axes_text})")
            given[axis.key] = axis.exact(value)
        return self._candidate(tuple((k, given[k]) for k in keys))

    def candidate_of(self, spring: dict) -> Candidate:
        """The candidate a spring.json document describes: its `design` values (and material) on this study's axes.

        Parameters
        ----------
        spring : dict
            A spring.json document (``design``: geometry in mm and deg, ``material``: its ``name``).

        Returns
        -------
        Candidate
            Unchecked (see `check`).

        Raises
        ------
        ConfigError
            The document lacks an axis's value, or the value is outside this study's design space (named).

        Examples
        --------
        >>> import seadesign as sd
        >>> sd.load_study("wolfgang_knee").candidate_of({"design": {"beam_count": 6, "beam_thickness_mm": 8.0}}).name
        '6 beams x 8 mm'
        """
        values = {}
        for axis in self.axes:
            node = spring.get("material", {}).get("name") if axis.key == MATERIAL_KEY else spring.get("design", {})
            for part in ([] if axis.key == MATERIAL_KEY else axis.key.split(".")):
                node = node.get(part) if isinstance(node, dict) else None
            if node is None:
                raise ConfigError(f"spring.json has no value for study '{self.name}''s axis {axis.key} "
                                  f"({'material/name' if axis.key == MATERIAL_KEY else 'design/' + axis.key.replace('.', '/')})")
            values[axis.key] = node
        return self.candidate(**values)

    def check(self, candidate: Candidate) -> tuple[Candidate, "Part"]:
        """Build a candidate's solid with CadQuery and check it with this study's validity rules.

        Parameters
        ----------
        candidate : Candidate
            One of this study's candidates.

        Returns
        -------
        Candidate
            The candidate checked: its validity reasons (none: valid), volume (mm^3) and mass (kg).
        Part
            The CAD part (its solid, and its volume in mm^3).

        A solid CadQuery cannot build is not raised: it comes back invalid, with the failure among its reasons.

        Examples
        --------
        >>> import seadesign as sd
        >>> study = sd.load_study("wolfgang_knee")
        >>> checked, part = study.check(study.candidate(beam_count=6, beam_thickness_mm=8.0))
        >>> checked.valid, round(checked.mass_kg * 1e3, 1)
        (True, 28.3)
        """
        return check_candidate(candidate, self.validity)

    def candidate_of_row(self, row) -> Candidate:
        """The candidate a results-table row belongs to.

        Parameters
        ----------
        row : mapping or pandas.Series
            A row with one column per design axis (as ``results.csv`` and ``SweepResult.to_frame()`` hold).

        Returns
        -------
        Candidate
            Unchecked.

        Raises
        ------
        ConfigError
            The row's values are outside the study's design space.

        Examples
        --------
        >>> import seadesign as sd
        >>> study = sd.load_study("wolfgang_knee")
        >>> study.candidate_of_row({"beam_count": 6, "beam_thickness_mm": 8.0}).name
        '6 beams x 8 mm'
        """
        return self.candidate(**{a.key: row[a.key] if a.key == MATERIAL_KEY else
                                 (float if a.continuous else type(a.values[0]))(row[a.key]) for a in self.axes})

    def _candidate(self, values: tuple[tuple[str, Value], ...]) -> Candidate:
        origins = {f"geometry.{key}": f"design_space.{key}" + ("" if axis.continuous else f"[{axis.values.index(v)}]")
                   for axis, (key, v) in zip(self.axes, values)}
        params = read_geometry(Table(merged(self.fixed, values), self.path, "geometry", origins))
        if self.bearing_radius_mm > params.hub_radius_mm + 1e-9:
            raise ConfigError(f"{self.path}: bearing_radius_mm must not exceed geometry.hub_radius_mm "
                              "(it is read on the hub)")
        material = self.materials[dict(values).get(MATERIAL_KEY, next(iter(self.materials)))]
        return Candidate(values, params, material)


def _materials(top: Table, axes: tuple[Axis, ...]) -> tuple[dict[str, Material], dict[str, InputFile]]:
    """The fixed material (top-level `material`), or each value of a `material` design axis, and their files."""
    axis = next((a for a in axes if a.key == MATERIAL_KEY), None)
    if axis is not None and "material" in top.data:
        raise top.error("material", "is also a design axis (design_space.material); a key is either a design axis "
                                    "or a fixed value: remove one of them")
    names, where = (axis.values, "design_space.material") if axis else ((top.string("material"),), "material")
    materials, files = {}, {}
    for name in names:
        try:
            path = MATERIAL.find(name)
            materials[name], files[name] = load_material_file(path), InputFile.of(path)
        except ConfigError as exc:
            raise top.error(where, f"cannot be loaded: {exc}") from None
    return materials, files


def _validity(top: Table) -> ValidityRules:
    v = top.table("validity")
    rules = ValidityRules(v.number("min_clearance_mm", gt=0), v.number("min_feature_mm", gt=0),
                          v.number("min_wall_mm", gt=0))
    v.done()
    return rules


def _mesh(top: Table) -> MeshSettings:
    m = top.table("mesh")
    mesh = MeshSettings(m.number("elements_across_beam", gt=0), m.string("backend", "gmsh"),
                        m.number("elements_per_circle", 0.0, ge=0), m.number("layers", 0.0, ge=0))
    m.done()
    if mesh.backend not in ("pytetwild", "gmsh"):
        raise m.error(m.key("backend"), f"must be 'pytetwild' or 'gmsh', got '{mesh.backend}'")
    if mesh.backend != "gmsh" and mesh.elements_per_circle > 0:
        raise m.error(m.key("elements_per_circle"), "curvature-based sizing needs backend = 'gmsh'; set it to 0 "
                                                    "for pytetwild")
    return mesh


REMOVED_RANKING_KEYS = {  # [ranking] keys of earlier versions, and what replaced them
    "small_deflection_limit_rad": "the large-deflection path replaced the small-deflection flag",
    "contact_is_end_stop": "the path goes on through frictionless self-contact (spring.json schema 3), so a closing "
                           "gap is no longer an end stop that carries the rest",
    "self_contact": "the path always goes on through frictionless self-contact (spring.json schema 3)",
}


def _ranking(top: Table) -> tuple[Ranking, Requirements]:
    """[ranking] and [requirements] (see design/requirements.py)."""
    rk = top.table("ranking")
    for key, why in REMOVED_RANKING_KEYS.items():
        if rk.raw(key) is not None:
            raise rk.error(rk.key(key), f"is no longer used: {why}; remove the line")
    ranking = Ranking(
        safety_factor=rk.number("safety_factor", ge=1),
        impact_speed_m_per_s=rk.number("impact_speed_m_per_s", gt=0),
        knee_inertia_kg_m2=rk.number("knee_inertia_kg_m2", gt=0),
    )
    refuse_moved_keys(rk)
    rk.done()
    return ranking, read_requirements(top.table("requirements", optional=True))


def load_study(path: str | Path = DEFAULT_STUDY) -> Study:
    """Load and validate a study by path or by name (the working directory's NAME.toml, else the packaged one)."""
    path = STUDY.find(path)
    top = Table(read_toml(path), path)
    name = top.string("name")
    description = top.string("description")
    bearing_radius_mm = top.number("bearing_radius_mm", gt=0)
    fixed = top.raw("geometry", None)
    if not isinstance(fixed, dict):
        raise top.error("geometry", "is missing or not a table; add [geometry] with the fixed dimensions (mm, deg)")
    axes = read_axes(top.table("design_space"), fixed)
    robot = read_robot(top)
    ranking, requirements = _ranking(top)
    materials, material_files = _materials(top, axes)
    study = Study(name, description, path, materials, axes, fixed, _validity(top), read_load_cases(top, robot), robot,
                  read_actuator(top), _mesh(top), ranking, bearing_radius_mm, requirements,
                  StudyFiles(InputFile.of(path), material_files))
    top.done()
    check_window(study.k_window, str(path))
    if all(not a.continuous for a in axes):
        study.candidates()  # every combination is checked now, so a bad value is named before any work starts
    else:
        study.candidate(**{a.key: sum(a.bounds) / 2 if a.continuous else a.values[0] for a in axes})
    return study
