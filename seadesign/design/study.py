"""Study files (`studies/*.toml`): the design space, fixed geometry, material, load cases,
robot/actuator data, mesh and ranking settings of one design problem.

Every key is validated (present, typed, in range, no unknown keys); derived quantities such
as the impact torque are computed here from physical inputs, never typed in.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from seadesign.errors import ConfigError
from seadesign.design.materials import Material, load_material
from seadesign.design.params import BoltPattern, GeometryParams, NutSlots, ValidityRules
from seadesign.design.tomlcheck import Table, find_toml, read_toml

STUDIES_DIR = Path(__file__).resolve().parents[2] / "studies"
DEFAULT_STUDY = STUDIES_DIR / "wolfgang_knee.toml"
G = 9.80665  # m/s^2


@dataclass(frozen=True)
class LoadCases:
    """The two load cases as physical inputs (SI)."""

    stall_torque_Nm: float  # servo stall torque, applied on the hub
    foot_cell_force_N: float  # largest single load-cell reading at impact
    foot_cell_count: int  # cells per foot; the thesis took max cell x count
    lower_leg_m: float  # knee to foot lever
    impact_knee_angle_deg: float  # angle between force and lever at impact

    @property
    def foot_force_N(self) -> float:
        return self.foot_cell_force_N * self.foot_cell_count

    @property
    def impact_torque_Nm(self) -> float:
        """tau = r F sin(theta) (thesis eq. 5.1), applied on the backplate side."""
        return self.lower_leg_m * self.foot_force_N * math.sin(math.radians(self.impact_knee_angle_deg))


@dataclass(frozen=True)
class Robot:
    """Robot data for the standing load and the simulator (SI)."""

    mass_kg: float
    upper_leg_m: float
    lower_leg_m: float
    standing_knee_flexion_deg: float  # knee bend when standing

    @property
    def standing_knee_torque_Nm(self) -> float:
        """Static knee torque standing on two legs: half the weight acting on the lower leg's
        horizontal lever, lower_leg sin(flexion / 2) (hip above ankle, both segments tilted
        by half the flexion)."""
        return self.mass_kg * G / 2 * self.lower_leg_m * math.sin(math.radians(self.standing_knee_flexion_deg) / 2)


@dataclass(frozen=True)
class Actuator:
    """Servo data (the stall torque lives in the load cases)."""

    gear_ratio: float
    no_load_speed_rpm: float
    backlash_deg: float


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
    """Constraints and objective weights for choosing a candidate."""

    safety_factor: float  # peak stress must stay below yield / safety_factor
    max_standing_deflection_deg: float  # knee deflection under the standing load
    k_min_Nm_per_rad: float | None
    k_max_Nm_per_rad: float | None
    small_deflection_limit_rad: float  # beyond it a linear solution is an extrapolation
    impact_speed_m_per_s: float  # foot speed at touchdown
    knee_inertia_kg_m2: float  # inertia of the link behind the spring, about the knee
    weight_accuracy: float
    weight_protection: float


@dataclass(frozen=True)
class Study:
    name: str
    description: str
    path: Path
    material: Material
    beam_counts: tuple[int, ...]
    beam_thicknesses_mm: tuple[float, ...]
    base: dict  # fixed geometry keyword arguments of GeometryParams
    validity: ValidityRules
    load_cases: LoadCases
    robot: Robot
    actuator: Actuator
    mesh: MeshSettings
    ranking: Ranking
    bearing_radius_mm: float  # where the stall displacement is read (thesis eq. 5.3)

    def candidates(self) -> list[GeometryParams]:
        """Every (beam count, thickness) combination, thickness-major like the thesis."""
        return [self.params(n, t) for t in self.beam_thicknesses_mm for n in self.beam_counts]

    def params(self, beam_count: int, beam_thickness_mm: float) -> GeometryParams:
        return GeometryParams(beam_count=beam_count, beam_thickness_mm=beam_thickness_mm, **self.base)


def _bolts(t: Table, name: str) -> BoltPattern:
    b = t.table(name)
    pattern = BoltPattern(
        count=b.integer("count", ge=1),
        circle_diameter_mm=b.number("circle_diameter_mm", gt=0),
        hole_diameter_mm=b.number("hole_diameter_mm", gt=0),
        start_angle_deg=b.number("start_angle_deg", 0.0),
        counterbore_diameter_mm=b.number("counterbore_diameter_mm", 0.0, ge=0),
        counterbore_depth_mm=b.number("counterbore_depth_mm", 0.0, ge=0),
    )
    b.done()
    if pattern.counterbore_diameter_mm and pattern.counterbore_diameter_mm <= pattern.hole_diameter_mm:
        raise b.error(b.key("counterbore_diameter_mm"), "must be larger than hole_diameter_mm")
    return pattern


def _geometry(t: Table) -> dict:
    g = t.table("geometry")
    base = dict(
        hub_radius_mm=g.number("hub_radius_mm", gt=0),
        arc_radius_mm=g.number("arc_radius_mm", gt=0),
        ring_width_mm=g.number("ring_width_mm", gt=0),
        thickness_mm=g.number("thickness_mm", gt=0),
        first_beam_angle_deg=g.number("first_beam_angle_deg"),
        clockwise=g.boolean("clockwise"),
        fillet_radius_mm=g.number("fillet_radius_mm", ge=0),
        bore_radius_mm=g.number("bore_radius_mm", 0.0, ge=0),
        hub_bolts=_bolts(g, "hub_bolts"),
        ring_bolts=_bolts(g, "ring_bolts"),
    )
    profile = g.raw("bore_profile_mm", [])
    if not isinstance(profile, list) or any(
        not isinstance(p, list) or len(p) != 2 or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in p)
        for p in profile
    ):
        raise g.error(g.key("bore_profile_mm"), "must be a list of [z_mm, radius_mm] pairs")
    base["bore_profile_mm"] = tuple((float(z), float(r)) for z, r in profile)
    slots = g.table("nut_slots", optional=True)
    if slots is not None:
        base["nut_slots"] = NutSlots(slots.number("width_mm", gt=0), slots.number("z_min_mm", ge=0),
                                     slots.number("z_max_mm", gt=0))
        slots.done()
    g.done()

    # Impossible combinations, named by key.
    hub_r = base["hub_radius_mm"]
    ring_in = hub_r + 2 * base["arc_radius_mm"]
    ring_out = ring_in + base["ring_width_mm"]
    bore = max([base["bore_radius_mm"]] + [r for _, r in base["bore_profile_mm"]])
    if bore >= hub_r:
        raise g.error(g.key("bore_radius_mm"), f"({bore:g} mm) must be smaller than hub_radius_mm ({hub_r:g} mm)")
    for name, lo, hi in (("hub_bolts", bore, hub_r), ("ring_bolts", ring_in, ring_out)):
        pat: BoltPattern = base[name]
        r = pat.circle_diameter_mm / 2
        if not lo < r - pat.hole_diameter_mm / 2 or not r + pat.hole_diameter_mm / 2 < hi:
            raise g.error(g.key(f"{name}.circle_diameter_mm"),
                          f"puts the holes (radius {r:g} mm +- {pat.hole_diameter_mm / 2:g}) outside the "
                          f"{'hub' if name == 'hub_bolts' else 'ring'} ({lo:g} to {hi:g} mm)")
    for z, r in base["bore_profile_mm"]:
        if not 0 <= z <= base["thickness_mm"] or not 0 < r:
            raise g.error(g.key("bore_profile_mm"), f"point [{z:g}, {r:g}] lies outside 0 <= z <= thickness_mm, r > 0")
    if "nut_slots" in base:
        s: NutSlots = base["nut_slots"]
        if not s.z_min_mm < s.z_max_mm <= base["thickness_mm"]:
            raise g.error(g.key("nut_slots"), "needs z_min_mm < z_max_mm <= thickness_mm")
    return base


def load_study(path: str | Path = DEFAULT_STUDY) -> Study:
    """Load and validate a study by path or by name (a file stem in `studies/`)."""
    path = find_toml(path, STUDIES_DIR, "study", "studies")
    top = Table(read_toml(path), path)
    name = top.string("name")
    description = top.string("description")
    try:
        material = load_material(top.string("material"))
    except ConfigError as exc:
        raise top.error("material", f"cannot be loaded: {exc}") from None
    bearing_radius_mm = top.number("bearing_radius_mm", gt=0)

    space = top.table("design_space")
    beam_counts = space.number_list("beam_count", integer=True, gt=0)
    thicknesses = space.number_list("beam_thickness_mm", gt=0)
    space.done()

    base = _geometry(top)
    if bearing_radius_mm > base["hub_radius_mm"] + 1e-9:
        raise top.error("bearing_radius_mm", "must not exceed geometry.hub_radius_mm (it is read on the hub)")
    for t in thicknesses:
        if t / 2 >= base["arc_radius_mm"]:
            raise space.error(space.key("beam_thickness_mm"),
                              f"value {t:g} mm needs geometry.arc_radius_mm > {t / 2:g} mm (half the beam width)")

    v = top.table("validity")
    validity = ValidityRules(v.number("min_clearance_mm", gt=0), v.number("min_feature_mm", gt=0),
                             v.number("min_wall_mm", gt=0))
    v.done()

    lc = top.table("load_cases")
    load_cases = LoadCases(
        stall_torque_Nm=lc.number("stall_torque_Nm", gt=0),
        foot_cell_force_N=lc.number("foot_cell_force_N", gt=0),
        foot_cell_count=lc.integer("foot_cell_count", ge=1),
        lower_leg_m=lc.number("lower_leg_m", gt=0),
        impact_knee_angle_deg=lc.number("impact_knee_angle_deg", gt=0, lt=180),
    )
    lc.done()

    r = top.table("robot")
    robot = Robot(r.number("mass_kg", gt=0), r.number("upper_leg_m", gt=0), r.number("lower_leg_m", gt=0),
                  r.number("standing_knee_flexion_deg", ge=0, lt=180))
    r.done()

    a = top.table("actuator")
    actuator = Actuator(a.number("gear_ratio", gt=0), a.number("no_load_speed_rpm", gt=0), a.number("backlash_deg", ge=0))
    a.done()

    m = top.table("mesh")
    mesh = MeshSettings(m.number("elements_across_beam", gt=0), m.string("backend", "gmsh"),
                        m.number("elements_per_circle", 0.0, ge=0), m.number("layers", 0.0, ge=0))
    m.done()
    if mesh.backend not in ("pytetwild", "gmsh"):
        raise m.error(m.key("backend"), f"must be 'pytetwild' or 'gmsh', got '{mesh.backend}'")
    if mesh.backend != "gmsh" and mesh.elements_per_circle > 0:
        raise m.error(m.key("elements_per_circle"), "curvature-based sizing needs backend = 'gmsh'; set it to 0 "
                                                    "for pytetwild")

    rk = top.table("ranking")
    ranking = Ranking(
        safety_factor=rk.number("safety_factor", ge=1),
        max_standing_deflection_deg=rk.number("max_standing_deflection_deg", gt=0),
        k_min_Nm_per_rad=rk.number("k_min_Nm_per_rad", gt=0, required=False),
        k_max_Nm_per_rad=rk.number("k_max_Nm_per_rad", gt=0, required=False),
        small_deflection_limit_rad=rk.number("small_deflection_limit_rad", gt=0),
        impact_speed_m_per_s=rk.number("impact_speed_m_per_s", gt=0),
        knee_inertia_kg_m2=rk.number("knee_inertia_kg_m2", gt=0),
        weight_accuracy=rk.number("weight_accuracy", ge=0),
        weight_protection=rk.number("weight_protection", ge=0),
    )
    rk.done()
    top.done()
    if ranking.weight_accuracy + ranking.weight_protection <= 0:
        raise ConfigError(f"{path}: ranking.weight_accuracy + ranking.weight_protection must be > 0")

    return Study(name, description, path, material, beam_counts, thicknesses, base, validity, load_cases,
                 robot, actuator, mesh, ranking, bearing_radius_mm)
