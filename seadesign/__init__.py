"""seadesign: design, verify and calibrate the 3D-printed torsion spring of a series elastic actuator.

``import seadesign as sd`` gives the entry points, with the command line's defaults::

    study = sd.load_study("wolfgang_knee")
    path = sd.torque_path(study, study.candidate(beam_count=3, beam_thickness_mm=8.0))
    path.plot()

Each name is imported on first use (PEP 562), so ``import seadesign`` loads neither CadQuery nor PyTorch.
"""

from importlib import import_module
from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("seadesign")
except PackageNotFoundError:  # running from a source tree without install
    __version__ = "0.0.0+src"

#: public name -> (module, attribute): where each entry point lives
_ENTRY_POINTS = {
    "load_study": ("seadesign.api", "load_study"),
    "load_material": ("seadesign.api", "load_material"),
    "geometry": ("seadesign.api", "geometry"),
    "export": ("seadesign.api", "export"),
    "solve": ("seadesign.sweep.single", "solve_candidate"),
    "solve_stl": ("seadesign.sweep.single", "solve_stl"),
    "torque_path": ("seadesign.sweep.single", "candidate_path"),
    "sweep_study": ("seadesign.sweep.pipeline", "sweep_study"),
    "apply_calibration": ("seadesign.sweep.pipeline", "apply_calibration"),
    "run_exploration": ("seadesign.explore.pipeline", "run_exploration"),
    "train": ("seadesign.corrector.pipeline", "train"),
    "evaluate": ("seadesign.corrector.pipeline", "evaluate"),
    "explain": ("seadesign.calibration.explain_file", "explain_file"),
    "simulate": ("seadesign.twin.pipeline", "simulate_walk"),
    "simulate_bench": ("seadesign.twin.pipeline", "simulate_bench_test"),
    "inspect_recording": ("seadesign.data.pipeline", "inspect_recording"),
    "clean_recording": ("seadesign.data.pipeline", "clean_recording"),
    "Study": ("seadesign.design.study", "Study"),
    "Candidate": ("seadesign.design.candidate", "Candidate"),
    "Material": ("seadesign.design.materials", "Material"),
    "LinearSolve": ("seadesign.sweep.single", "LinearSolve"),
    "CandidatePath": ("seadesign.sweep.single", "CandidatePath"),
    "SweepResult": ("seadesign.sweep.pipeline", "SweepResult"),
    "ExplorationResult": ("seadesign.explore.pipeline", "ExplorationResult"),
    "TrainedCorrector": ("seadesign.corrector.pipeline", "TrainedCorrector"),
    "FileExplanation": ("seadesign.calibration.explain_file", "FileExplanation"),
    "Thresholds": ("seadesign.data.artefacts", "Thresholds"),
    "SeadesignError": ("seadesign.errors", "SeadesignError"),
    "ConfigError": ("seadesign.errors", "ConfigError"),
}

__all__ = ["__version__", *_ENTRY_POINTS]


def __getattr__(name: str):
    """The entry point `name`, imported on first use."""
    try:
        module, attribute = _ENTRY_POINTS[name]
    except KeyError:
        raise AttributeError(f"module 'seadesign' has no attribute {name!r}") from None
    value = getattr(import_module(module), attribute)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_ENTRY_POINTS})
