"""Material files (`materials/*.toml`): loading, unit conversion to SI, validation.

Each property is a table `{ value = ..., unit = "...", source = "..." }`; the loader converts
to SI (Pa, kg/m^3) and rejects anything missing, non-numeric or outside a physical range.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path

from seadesign.design.tomlcheck import Table, find_toml, read_toml

MATERIALS_DIR = Path(__file__).resolve().parents[2] / "materials"

_TO_PA = {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9}
_TO_KG_M3 = {"kg/m^3": 1.0, "kg/m3": 1.0, "g/cc": 1000.0, "g/cm^3": 1000.0, "g/cm3": 1000.0}
_DIMENSIONLESS = {"-": 1.0, "1": 1.0}

# (key, unit table, SI range (lo, hi), range is exclusive)
_FIELDS = {
    "youngs_modulus": (_TO_PA, (1e5, 1e12)),
    "poisson_ratio": (_DIMENSIONLESS, (0.0, 0.5)),
    "density": (_TO_KG_M3, (10.0, 25000.0)),
    "yield_strength": (_TO_PA, (1e4, 1e10)),
    "tensile_strength": (_TO_PA, (1e4, 1e10)),
}


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

    @property
    def shear_modulus_Pa(self) -> float:
        return self.youngs_modulus_Pa / (2.0 * (1.0 + self.poisson_ratio))

    def scaled(self, stiffness_scale: float, note: str) -> "Material":
        """The same material with E multiplied by `stiffness_scale` (a calibration result)."""
        data = asdict(self)
        data["youngs_modulus_Pa"] = self.youngs_modulus_Pa * stiffness_scale
        data["name"] = f"{self.name} ({note})"
        data["sources"] = tuple(tuple(s) for s in self.sources) + (("youngs_modulus", note),)
        return Material(**data)

    def to_handoff(self) -> dict:
        """The material block of spring.json."""
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
    )


def load_material(name_or_path: str | Path, materials_dir: Path = MATERIALS_DIR) -> Material:
    """Load a material by file stem (e.g. "ninjaflex") from `materials/`, or by path."""
    return load_material_file(find_toml(name_or_path, materials_dir, "material", "materials"))
