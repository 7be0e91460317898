"""Material files: the shipped ones load in SI; bad files are refused naming file and field."""

from pathlib import Path

import pytest

from seadesign.errors import ConfigError
from seadesign.design.inputs import MATERIAL
from seadesign.design.materials import load_material, load_material_file

GOOD = """
name = "Test TPU"
youngs_modulus = { value = 12.0, unit = "MPa", source = "test" }
poisson_ratio = { value = 0.48, unit = "-", source = "test" }
density = { value = 1.19, unit = "g/cc", source = "test" }
yield_strength = { value = 4.0, unit = "MPa", source = "test" }
tensile_strength = { value = 26.0, unit = "MPa", source = "test" }
"""


def test_shipped_materials_load_in_si():
    names = sorted(p.stem for p in MATERIAL.packaged.glob("*.toml"))
    assert {"ninjaflex", "cheetah", "pla", "brass", "generic_tpu"} <= set(names)
    nf = load_material("ninjaflex")
    assert nf.youngs_modulus_Pa == pytest.approx(12e6)
    assert nf.density_kg_per_m3 == pytest.approx(1190.0)
    assert load_material("generic_tpu").youngs_modulus_Pa == pytest.approx(0.147e9)
    # the thesis's brass typo (1096 GPa) is fixed
    assert 100e9 <= load_material("brass").youngs_modulus_Pa <= 110e9
    for name in names:
        m = load_material(name)
        assert 0 <= m.poisson_ratio < 0.5
        assert all(src for _, src in m.sources)


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "bad.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda t: t.replace('poisson_ratio = { value = 0.48', 'poisson_ratio = { value = 0.5'), "poisson_ratio.value"),
        (lambda t: t.replace('value = 12.0', 'value = "twelve"'), "youngs_modulus.value must be a number"),
        (lambda t: t.replace('unit = "MPa", source = "test" }\npoisson', 'unit = "psi", source = "test" }\npoisson'),
         "youngs_modulus.unit"),
        (lambda t: t.replace('value = 12.0, unit = "MPa"', 'value = 12.0, unit = "Pa"'), "physical range"),
        (lambda t: t.replace('density = { value = 1.19, unit = "g/cc", source = "test" }\n', ''), "density is missing"),
        (lambda t: t + 'colour = "red"\n', "colour is not a known key"),
        (lambda t: t.replace(', source = "test" }\ndensity', ' }\ndensity'), "poisson_ratio.source is missing"),
    ],
)
def test_bad_material_files_are_refused(tmp_path, edit, message):
    path = _write(tmp_path, edit(GOOD))
    with pytest.raises(ConfigError) as err:
        load_material_file(path)
    assert str(path) in str(err.value)
    assert message in str(err.value)


def test_unknown_material_lists_known():
    with pytest.raises(ConfigError, match="nor among the packaged materials in .*ninjaflex"):
        load_material("unobtainium")


def test_toml_syntax_error(tmp_path):
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_material_file(_write(tmp_path, "name = "))


def test_strain_limits_and_the_derived_hyperelastic_law():
    nf = load_material("ninjaflex")
    assert nf.elongation_at_yield == pytest.approx(0.65)
    assert nf.strain_limits(1.5).single == pytest.approx(0.65 / 1.5)
    assert nf.strain_limits(1.5).cyclic is None  # no sourced cyclic limit: the repeating loads cannot be judged
    assert load_material("cheetah").strain_limits(1.5).single is None  # no sourced value: cannot be judged
    law = nf.law  # E 12 MPa, nu 0.48 -> C10 = mu / 2 = 2.03 MPa, D1 = 2 / K = 0.020 1/MPa
    assert law.model == "neo_hooke"
    assert law.c10_Pa == pytest.approx(12e6 / (2 * 1.48) / 2)
    assert law.d1_per_Pa == pytest.approx(2 / (12e6 / (3 * (1 - 0.96))))
    soft = nf.scaled(0.5, "test").law
    assert soft.c10_Pa == pytest.approx(law.c10_Pa / 2) and soft.d1_per_Pa == pytest.approx(law.d1_per_Pa * 2)


def test_a_cyclic_strain_limit_is_read_and_must_stay_below_the_elongation_at_yield(tmp_path):
    yield_65 = GOOD + 'elongation_at_yield = { value = 65.0, unit = "%", source = "test" }\n'
    m = load_material_file(_write(tmp_path, yield_65 + 'cyclic_strain_limit = { value = 20.0, unit = "%", source = "t" }\n'))
    assert m.cyclic_strain_limit == pytest.approx(0.2) and m.strain_limits(1.5).at("stall") == pytest.approx(0.2)
    assert m.strain_limits(1.5).at("impact") == pytest.approx(0.65 / 1.5)
    with pytest.raises(ConfigError, match=r"cyclic_strain_limit \(70 %\) must not exceed elongation_at_yield \(65 %\)"):
        load_material_file(_write(tmp_path, yield_65 + 'cyclic_strain_limit = { value = 70.0, unit = "%", source = "t" }\n'))
    with pytest.raises(ConfigError, match=r"cyclic_strain_limit \(20 %\) must not exceed elongation_at_yield \(not given\)"):
        load_material_file(_write(tmp_path, GOOD + 'cyclic_strain_limit = { value = 20.0, unit = "%", source = "t" }\n'))


def test_a_hyperelastic_table_is_read_in_si_and_checked(tmp_path):
    text = GOOD + ('hyperelastic = { model = "mooney_rivlin", source = "test fit", c10 = { value = 1.5, unit = "MPa" }, '
                   'c01 = { value = 0.3, unit = "MPa" }, d1 = { value = 0.02, unit = "1/MPa" } }\n')
    m = load_material_file(_write(tmp_path, text))
    assert (m.law.model, m.law.c10_Pa, m.law.c01_Pa, m.law.d1_per_Pa) == ("mooney_rivlin", 1.5e6, 0.3e6, 2e-8)
    assert m.scaled(2.0, "x").law.c01_Pa == pytest.approx(0.6e6)
    with pytest.raises(ConfigError, match="hyperelastic.model.*'ogden' is not a known model"):
        load_material_file(_write(tmp_path, GOOD + 'hyperelastic = { model = "ogden", source = "x" }\n'))
    with pytest.raises(ConfigError, match="hyperelastic.c01 is missing"):
        load_material_file(_write(tmp_path, text.replace('c01 = { value = 0.3, unit = "MPa" }, ', '')))
    with pytest.raises(ConfigError, match="elongation_at_yield.unit"):
        load_material_file(_write(tmp_path, GOOD + 'elongation_at_yield = { value = 65, unit = "percent", source = "x" }\n'))
