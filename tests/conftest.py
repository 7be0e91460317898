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
def one_torch_thread():
    """One intra-op torch thread for the test (small batches: faster than two, as training sets it)."""
    import torch

    before = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(before)


@pytest.fixture
def ccx() -> str:
    """CalculiX, the independent solver."""
    return require_tool("ccx", "Debian: apt-get install calculix-ccx")


@pytest.fixture
def spring_dict() -> dict:
    """A valid spring.json payload: the thesis's measured 9-beam 8 mm NinjaFlex spring on the Wolfgang-OP knee."""
    return thesis_spring()


def thesis_spring() -> dict:
    """The payload of `spring_dict` (studies/thesis_measured_spring.json), for module-scoped fixtures."""
    from seadesign.design.spring import load_spring

    return load_spring(Path(__file__).resolve().parents[1] / "studies" / "thesis_measured_spring.json")


@pytest.fixture
def spring_file(tmp_path, spring_dict) -> Path:
    """spring_dict written to a file through the validating writer."""
    from seadesign.design.spring import write_spring

    return write_spring(spring_dict, tmp_path / "spring.json")
