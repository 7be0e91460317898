"""Material files (`materials/*.toml`, packaged with seadesign; see `inputs.py`): loading, unit conversion to SI,
validation.

Each property is a table `{ value = ..., unit = "...", source = "..." }`; the loader converts
to SI (Pa, kg/m^3, 1/Pa, strain as a fraction) and rejects anything missing, non-numeric or
outside a physical range. Two optional entries serve the large-deflection analysis:
`elongation_at_yield` (the single-event allowable strain's basis) and `cyclic_strain_limit` (the
allowable tensile strain of loads repeated millions of times, at most the elongation at yield), each with
its source; without one, the strain requirement of its load class cannot be judged and is not met (results
say which datum is missing and what value would pass), and `hyperelastic`, the finite-strain law in
CalculiX's form (`model = "neo_hooke" | "mooney_rivlin" | "yeoh"` with its constants and a
source). Without `hyperelastic`, a neo-Hookean law is derived from E and nu (C10 = mu / 2,
D1 = 2 / K), so the small-strain limit is exactly the linear model.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, replace
from pathlib import Path

from seadesign.design.inputs import MATERIAL
from seadesign.design.tomlcheck import Table, read_toml

_TO_PA = {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9}
_TO_KG_M3 = {"kg/m^3": 1.0, "kg/m3": 1.0, "g/cc": 1000.0, "g/cm^3": 1000.0, "g/cm3": 1000.0}
_DIMENSIONLESS = {"-": 1.0, "1": 1.0}
_STRAIN = {"%": 0.01, "-": 1.0}
_PER_PA = {"1/Pa": 1.0, "1/kPa": 1e-3, "1/MPa": 1e-6}
# the constants of each hyperelastic model (CalculiX *HYPERELASTIC): name -> unit table
HYPERELASTIC_MODELS = {
    "neo_hooke": ("c10", "d1"),
    "mooney_rivlin": ("c10", "c01", "d1"),
    "yeoh": ("c10", "c20", "c30", "d1", "d2", "d3"),
}

# (key, unit table, SI range (lo, hi), range is exclusive)
_FIELDS = {
    "youngs_modulus": (_TO_PA, (1e5, 1e12)),
    "poisson_ratio": (_DIMENSIONLESS, (0.0, 0.5)),
    "density": (_TO_KG_M3, (10.0, 25000.0)),
    "yield_strength": (_TO_PA, (1e4, 1e10)),
    "tensile_strength": (_TO_PA, (1e4, 1e10)),
}


@dataclass(frozen=True)
class Hyperelastic:
    """A finite-strain law in CalculiX's form: W = sum Cij (I1bar - 3)^i (I2bar - 3)^j + sum (J - 1)^(2k) / Dk.
    Moduli in Pa, compressibilities in 1/Pa (0: term absent); `source` says where they come from."""

    model: str  # "neo_hooke", "mooney_rivlin" or "yeoh"
    c10_Pa: float
    d1_per_Pa: float
    source: str
    c01_Pa: float = 0.0
    c20_Pa: float = 0.0
    c30_Pa: float = 0.0
    d2_per_Pa: float = 0.0
    d3_per_Pa: float = 0.0

    @classmethod
    def from_linear(cls, youngs_modulus_Pa: float, poisson_ratio: float) -> "Hyperelastic":
        """The neo-Hookean law whose small-strain limit is the linear model (E, nu)."""
        mu = youngs_modulus_Pa / (2.0 * (1.0 + poisson_ratio))
        bulk = youngs_modulus_Pa / (3.0 * (1.0 - 2.0 * poisson_ratio))
        return cls("neo_hooke", c10_Pa=mu / 2.0, d1_per_Pa=2.0 / bulk,
                   source="derived from E and nu: C10 = mu / 2, D1 = 2 / K (small-strain limit = the linear model)")

    @property
    def shear_modulus_Pa(self) -> float:
        """The initial shear modulus mu = 2 (C10 + C01) (Pa)."""
        return 2.0 * (self.c10_Pa + self.c01_Pa)

    def scale_of(self, other: "Hyperelastic") -> float | None:
        """s where this law is `other` with every modulus times s and every compressibility over s (each to 1e-12
        relative), else None: a stiffness calibration of `other` (`Material.scaled`)."""
        s = self.shear_modulus_Pa / other.shear_modulus_Pa
        pairs = [(getattr(self, f), s * getattr(other, f)) for f in ("c10_Pa", "c01_Pa", "c20_Pa", "c30_Pa")]
        pairs += [(getattr(self, f), getattr(other, f) / s) for f in ("d1_per_Pa", "d2_per_Pa", "d3_per_Pa")]
        same = self.model == other.model and all(abs(a - b) <= 1e-12 * max(abs(a), abs(b)) for a, b in pairs)
        return s if same else None


@dataclass(frozen=True)
class StrainLimits:
    """The allowable tensile engineering strains of the two load classes (None: no sourced value, so the
    strain there cannot be judged): repeating loads (standing, walking up to the stall torque) against the
    material's cyclic strain limit, the single impact against elongation at yield / safety factor."""

    cyclic: float | None
    single: float | None

    def at(self, load: str) -> float | None:
        """The limit that applies to a load: the single-event one at impact, the cyclic one elsewhere."""
        return self.single if load == "impact" else self.cyclic


@dataclass(frozen=True)
class Material:
    """An isotropic linear-elastic material in SI units."""

    key: str  # file stem, e.g. "ninjaflex"
    name: str
    youngs_modulus_Pa: float
    poisson_ratio: float
    density_kg_per_m3: float
    yield_strength_Pa: float
    tensile_strength_Pa: float
    sources: tuple[tuple[str, str], ...]  # (property, source) pairs
    hyperelastic: Hyperelastic | None = None  # None: derived from E and nu (see `law`)
    elongation_at_yield: float | None = None  # engineering strain (0.65 = 65 %); None: no sourced value
    cyclic_strain_limit: float | None = None  # tensile engineering strain for loads repeated millions of times
    scaled_from: Material | None = dataclasses.field(default=None, repr=False, compare=False)  # the material `scaled` scaled

    @property
    def law(self) -> Hyperelastic:
        """The finite-strain law: the file's, or the neo-Hookean one derived from E and nu."""
        return self.hyperelastic or Hyperelastic.from_linear(self.youngs_modulus_Pa, self.poisson_ratio)

    def strain_limits(self, safety_factor: float) -> StrainLimits:
        """The allowable tensile strains: the cyclic limit as sourced (no factor: the source's limit is already
        one for repeated loading) and elongation at yield / safety factor for a single event.

        Parameters
        ----------
        safety_factor : float
            Divides the elongation at yield (dimensionless, >= 1; the study's ``[strength] safety_factor``).

        Returns
        -------
        StrainLimits
            ``cyclic`` and ``single`` (event) tensile engineering strains (0.43 = 43 %); None where the material file
            has no sourced value (the verdict is then "not judged").

        Examples
        --------
        >>> import seadesign as sd
        >>> sd.load_material("ninjaflex").strain_limits(1.5)
        StrainLimits(cyclic=None, single=0.43333333333333335)
        """
        single = None if self.elongation_at_yield is None else self.elongation_at_yield / safety_factor
        return StrainLimits(self.cyclic_strain_limit, single)

    @property
    def shear_modulus_Pa(self) -> float:
        """Small-strain shear modulus E / (2 (1 + nu)) (Pa)."""
        return self.youngs_modulus_Pa / (2.0 * (1.0 + self.poisson_ratio))

    def scaled(self, stiffness_scale: float, note: str) -> "Material":
        """The same material with every modulus multiplied by `stiffness_scale` (a calibration result).

        Parameters
        ----------
        stiffness_scale : float
            Factor on E and on the hyperelastic law's moduli (dimensionless, > 0).
        note : str
            Where the scale comes from; added to the name and the sources.

        Returns
        -------
        Material
            A copy; this material is unchanged.

        Examples
        --------
        >>> import seadesign as sd
        >>> soft = sd.load_material("ninjaflex").scaled(0.5, "bench test 2026-11-20")
        >>> soft.youngs_modulus_Pa
        6000000.0
        """
        h, s = self.hyperelastic, stiffness_scale
        hyper = None if h is None else replace(
            h, c10_Pa=h.c10_Pa * s, c01_Pa=h.c01_Pa * s, c20_Pa=h.c20_Pa * s, c30_Pa=h.c30_Pa * s,
            d1_per_Pa=h.d1_per_Pa / s, d2_per_Pa=h.d2_per_Pa / s, d3_per_Pa=h.d3_per_Pa / s,
            source=f"{h.source}; x {s:.4g} ({note})")
        return replace(self, youngs_modulus_Pa=self.youngs_modulus_Pa * s, name=f"{self.name} ({note})",
                       sources=tuple(tuple(x) for x in self.sources) + (("youngs_modulus", note),), hyperelastic=hyper,
                       scaled_from=self.scaled_from or self)

    def to_handoff(self) -> dict:
        """The material block of spring.json.

        Returns
        -------
        dict
            ``name``, ``youngs_modulus_Pa``, ``poisson_ratio``, ``density_kg_per_m3``, ``yield_strength_Pa``.

        Examples
        --------
        >>> import seadesign as sd
        >>> sd.load_material("ninjaflex").to_handoff()["youngs_modulus_Pa"]
        12000000.0
        """
        return {
            "name": self.key,
            "youngs_modulus_Pa": self.youngs_modulus_Pa,
            "poisson_ratio": self.poisson_ratio,
            "density_kg_per_m3": self.density_kg_per_m3,
            "yield_strength_Pa": self.yield_strength_Pa,
        }


def _quantity(top: Table, field: str, units: dict[str, float], lo: float, hi: float) -> tuple[float, str]:
    sub = top.table(field)
    value = sub.number("value")
    unit = sub.string("unit")
    source = sub.string("source")
    sub.done()
    if unit not in units:
        raise sub.error(sub.key("unit"), f"'{unit}' is not a known unit here; use one of {', '.join(units)}")
    si = value * units[unit]
    if not lo < si < hi:
        raise sub.error(sub.key("value"), f"= {value:g} {unit} is outside the physical range "
                        f"({lo:g}, {hi:g}) in SI units; check the value and its unit")
    return si, source


def _hyperelastic(top: Table) -> Hyperelastic | None:
    sub = top.table("hyperelastic", optional=True)
    if sub is None:
        return None
    model = sub.string("model")
    if model not in HYPERELASTIC_MODELS:
        raise sub.error(sub.key("model"), f"'{model}' is not a known model; use one of {', '.join(HYPERELASTIC_MODELS)}")
    constants = {}
    for name in HYPERELASTIC_MODELS[model]:
        units = _PER_PA if name.startswith("d") else _TO_PA
        c = sub.table(name)
        value, unit = c.number("value"), c.string("unit")
        c.done()
        if unit not in units:
            raise c.error(c.key("unit"), f"'{unit}' is not a known unit here; use one of {', '.join(units)}")
        constants[f"{name}_{'per_Pa' if name.startswith('d') else 'Pa'}"] = value * units[unit]
    source = sub.string("source")
    sub.done()
    if not constants["c10_Pa"] > 0 or not constants["d1_per_Pa"] > 0:
        raise sub.error(sub.key("c10"), "and d1 must be positive (a stable material in the small-strain limit)")
    return Hyperelastic(model, source=source, **constants)


def load_material_file(path: str | Path) -> Material:
    """Load and validate one material file."""
    path = Path(path)
    top = Table(read_toml(path), path)
    name = top.string("name")
    values: dict[str, float] = {}
    sources = []
    for field, (units, (lo, hi)) in _FIELDS.items():
        values[field], src = _quantity(top, field, units, lo, hi)
        sources.append((field, src))
    strains = {}
    for field in ("elongation_at_yield", "cyclic_strain_limit"):
        if field in top.data:
            strains[field], src = _quantity(top, field, _STRAIN, 0.0, 20.0)
            sources.append((field, src))
    elongation, cyclic = strains.get("elongation_at_yield"), strains.get("cyclic_strain_limit")
    if cyclic is not None and (elongation is None or cyclic > elongation):
        raise top.error("cyclic_strain_limit", f"({100 * cyclic:.3g} %) must not exceed elongation_at_yield "
                        + ("(not given)" if elongation is None else f"({100 * elongation:.3g} %)")
                        + ": a limit for repeated loading lies below the single pull's yield; check both values "
                          "and their sources")
    hyper = _hyperelastic(top)
    top.done()
    return Material(
        key=path.stem,
        name=name,
        youngs_modulus_Pa=values["youngs_modulus"],
        poisson_ratio=values["poisson_ratio"],
        density_kg_per_m3=values["density"],
        yield_strength_Pa=values["yield_strength"],
        tensile_strength_Pa=values["tensile_strength"],
        sources=tuple(sources),
        hyperelastic=hyper,
        elongation_at_yield=elongation,
        cyclic_strain_limit=cyclic,
    )


def load_material(name_or_path: str | Path) -> Material:
    """Load a material by name (e.g. "ninjaflex": the working directory's file, else the packaged one) or by path."""
    return load_material_file(MATERIAL.find(name_or_path))
