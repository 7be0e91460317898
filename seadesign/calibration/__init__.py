"""Close the loop with measured data: the declared model refitted, missing effects traced, error before and after.

Generic engine (any table with a measured column, a prediction column and signals with roles):

- `LoopData`, `from_frame`, `ROLES` (`table.py`); `metrics` (`metrics.py`);
- `Term`, `CANDIDATES` (library keys the loop traces), `predict` (`terms.py`): where each effect of
  the one library (`seadesign.effects`) acts in the model;
- `EffectModel(terms).fit(data, held)` / `.predict` / `.score` / `.parameters()` (`model.py`);
- `explain(data, declared) -> Explanation` (`engine.py`); `residual_tests` (`whiteness.py`);
  `best_split` (`changepoint.py`).

SEA adapters (`sea.py`) build `LoopData` and the declared effects from a bench file or a robot
recording and a spring.json; `report.py` writes Markdown, HTML, JSON, plots and the calibration JSON.
"""

from seadesign.calibration.changepoint import best_split
from seadesign.calibration.engine import DeclaredCheck, Explanation, Step, TraceEntry, explain
from seadesign.calibration.metrics import metrics, split_metrics
from seadesign.calibration.model import EffectModel, Fit
from seadesign.calibration.table import ROLES, LoopData, LoopInputError, from_frame, time_blocks
from seadesign.calibration.terms import CANDIDATES, Term, predict
from seadesign.calibration.whiteness import residual_tests

__all__ = [
    "CANDIDATES", "ROLES", "DeclaredCheck", "EffectModel", "Explanation", "Fit", "LoopData", "LoopInputError", "Step",
    "Term", "TraceEntry", "best_split", "explain", "from_frame", "metrics", "predict", "residual_tests",
    "split_metrics", "time_blocks",
]
