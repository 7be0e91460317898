"""The knee spring as an explorer problem: a study's design axes, screened by the geometry stage and
evaluated by the sweep's full pipeline.

Screening is the sweep's geometry stage alone (CAD, validity, volume, mass: seconds, run in this process:
a round screens a couple of designs, less work than starting worker processes), so invalid
designs are learned by the classifier without a mesh or a solve, and the mass and envelope margins,
which screening gives exactly, are learned from every buildable design screened. Evaluation is the
sweep's per-candidate pipeline (`sweep.runner.run_candidates`: geometry, mesh, linear FEA, the
large-deflection path; its processes, stage cache, stored rows, progress and executors), judged by
the sweep's ranking columns and the study's requirements (`sweep/requirements.py`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from seadesign.design.space import MATERIAL_KEY
from seadesign.design.study import Study
from seadesign.errors import ConfigError
from seadesign.explore.encoding import Encoding
from seadesign.explore.problem import SOLVED, VALID
from seadesign.run.cache import Cache
from seadesign.run.progress import ProgressDisplay
from seadesign.sweep.physical import physical_columns
from seadesign.sweep.rank import constraint_columns
from seadesign.sweep.requirements import LOAD_CLASS, OBJECTIVE_COLUMNS, USABLE, envelope, lacks_limit, requirement_list
from seadesign.sweep.runner import run_candidates
from seadesign.sweep.stages import SolverSettings

# the physical outputs with a surrogate (units in the names): small-load k, mass, rotation at the stall
# torque, torque where the path stops (contact onset when it ends in contact), usable torque (where the tensile
# strain reaches the cyclic limit, or the path stops), standing sag
OUTPUTS = ("k_Nm_per_rad", "mass_g", "large_stall_rotation_rad", "large_stop_torque_Nm", USABLE,
           "standing_deflection_deg")
ENVELOPE_MARGINS = ("outer_diameter_margin", "thickness_margin")


@dataclass
class SpringProblem:
    """A study's design space as an explorer problem (see the module doc). Rows go to `out_dir`."""

    study: Study
    out_dir: Path
    settings: SolverSettings = SolverSettings()
    cache: Cache = field(default_factory=Cache)
    executor: str = "local"
    jobs: int | None = None
    scheduler: str | None = None
    display: ProgressDisplay | None = None  # progress of the full evaluations, kept across batches
    encoding: Encoding = field(init=False)

    def __post_init__(self) -> None:
        self.encoding = Encoding(self.study.axes)
        self.objectives = tuple(OBJECTIVE_COLUMNS[o] for o in self.study.requirements.objectives)
        self.margins = tuple(r.column for r in requirement_list(self.study))
        self.outputs = OUTPUTS
        self.screened = ("mass_g", *(m for m in ENVELOPE_MARGINS if m in self.margins))

    def unjudged(self, column: str, X: np.ndarray) -> np.ndarray:
        """Where a strain margin cannot be judged: designs of a material without a sourced limit for the load's
        class. The search models the rest, so it finds the best conditional design where nothing can be feasible."""
        none = np.zeros(len(X), bool)
        load = column.removesuffix("_strain_margin")
        if not column.endswith("_strain_margin") or load not in LOAD_CLASS:
            return none
        keys = self.encoding.keys
        if MATERIAL_KEY not in keys:
            return none | lacks_limit(self.study.material, load)
        axis = self.encoding.axes[keys.index(MATERIAL_KEY)]
        lacking = np.array([lacks_limit(self.study.materials[n], load) for n in axis.values])
        level = self.encoding.snap(X)[:, keys.index(MATERIAL_KEY)] * max(len(axis.values) - 1, 1)
        return lacking[np.rint(level).astype(int)]

    def candidates(self, X: np.ndarray):
        """The study's candidates at unit-cube designs X (None where the study refuses the geometry, with why)."""
        out = []
        for x in np.atleast_2d(X):
            try:
                out.append((self.study.candidate(**dict(self.encoding.decode(x))), ""))
            except ConfigError as exc:
                out.append((None, str(exc)))
        return out

    def screen(self, X: np.ndarray) -> pd.DataFrame:
        built = self.candidates(X)
        ok = [c for c, _ in built if c is not None]
        rows = iter(run_candidates(self.study, ok, self.out_dir, screen=True, settings=self.settings, cache=self.cache,
                                   executor="serial", quiet=True).rows.to_dict("records") if ok else [])
        table = pd.DataFrame([next(rows) if c is not None else
                              {**dict(self.encoding.decode(x)), "status": "invalid", "reason": why}
                              for x, (c, why) in zip(np.atleast_2d(X), built)])
        table[VALID] = table["status"] == "ok"
        valid = table[VALID]
        env = envelope(table[valid], self.study) if valid.any() else pd.DataFrame()
        req = self.study.requirements
        for column, key, limit in (("outer_diameter_margin", "outer_diameter_mm", req.max_outer_diameter_mm),
                                   ("thickness_margin", "axial_thickness_mm", req.max_thickness_mm)):
            if column in self.margins:
                table[column] = np.nan
                if valid.any():
                    table.loc[valid, column] = 1.0 - env[key] / limit
        return table

    def evaluate(self, X: np.ndarray) -> pd.DataFrame:
        candidates = [c for c, _ in self.candidates(X)]
        run = run_candidates(self.study, candidates, self.out_dir, settings=self.settings, cache=self.cache,
                             executor=self.executor, jobs=self.jobs, scheduler=self.scheduler, display=self.display,
                             quiet=self.display is None)
        t = constraint_columns(physical_columns(run.rows, self.study), self.study)
        t[SOLVED] = t["status"] == "ok"
        return t
