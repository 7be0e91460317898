"""Shared fixtures. Tests that need ../shared skip with a reason when it is absent."""

from __future__ import annotations

import importlib
import os
import shutil
from pathlib import Path
from types import ModuleType

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"


def shared_path(*parts: str) -> Path:
    """Path under ../shared, or skip the test with a clear reason when it is absent."""
    path = SHARED.joinpath(*parts)
    if not path.exists():
        pytest.skip(f"reference data {path} is not present (../shared is outside the repository)")
    return path


def require_tool(name: str, install: str) -> str:
    """Path of an external program; skip when it is missing, but fail under CI=true, where the
    CI script installs it and a skip would hide a broken install."""
    path = shutil.which(name)
    if path is None:
        message = f"`{name}` is not on PATH ({install})"
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail(message + "; CI installs it, so this test must run there")
        pytest.skip(message)
    return path


def require_module(name: str, install: str) -> ModuleType:
    """An optional Python package; skip when it is missing, but fail under CI=true, where the CI
    script installs it (as `require_tool`)."""
    try:
        return importlib.import_module(name)
    except ImportError:
        message = f"Python package `{name}` is not installed ({install})"
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail(message + "; CI installs it, so this test must run there")
        pytest.skip(message)


@pytest.fixture
def ccx() -> str:
    """CalculiX, the independent solver."""
    return require_tool("ccx", "Debian: apt-get install calculix-ccx")


@pytest.fixture
def spring_dict() -> dict:
    """A valid spring.json payload: the thesis's measured 9-beam 8 mm NinjaFlex spring on the Wolfgang-OP knee."""
    return thesis_spring()


def thesis_spring() -> dict:
    """The payload of `spring_dict`, for module-scoped fixtures."""
    return {
        "schema_version": 1,
        "study": "wolfgang_knee",
        "k_source": "measured",
        "k_Nm_per_rad": 9.106,
        "k_rel_error": None,
        "design": {"beam_count": 9, "beam_thickness_mm": 8.0},
        "material": {
            "name": "ninjaflex",
            "youngs_modulus_Pa": 12e6,
            "poisson_ratio": 0.48,
            "density_kg_per_m3": 1190.0,
            "yield_strength_Pa": 4e6,
        },
        "actuator": {
            "stall_torque_Nm": 11.7,
            "no_load_speed_rad_per_s": 46 * 2 * 3.141592653589793 / 60,
            "gear_ratio": 272.5,
            "backlash_rad": 0.25 * 3.141592653589793 / 180,
        },
        "robot": {"mass_kg": 8.0, "lower_leg_m": 0.2038, "upper_leg_m": 0.2},
        "inputs_hash": "0123456789abcdef",
        "versions": {"seadesign": "test"},
    }


@pytest.fixture
def spring_file(tmp_path, spring_dict) -> Path:
    """spring_dict written to a file through the validating writer."""
    from seadesign.design.spring import write_spring

    return write_spring(spring_dict, tmp_path / "spring.json")
