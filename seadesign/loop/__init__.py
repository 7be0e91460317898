"""Close the loop with measured data: residual, missing effect, refit, error before and after.

Generic engine (any table with a measured column, a prediction column and signals with roles):

- `LoopData`, `from_frame`, `ROLES` (`table.py`); `metrics` (`metrics.py`);
- `CANDIDATES` / `LIBRARY` of candidate effects (`candidates.py`), `fit` / `predict` (`fit.py`);
- `explain(data, declared) -> Explanation` (`engine.py`); `residual_tests` (`whiteness.py`).

SEA adapters (`sea.py`) build `LoopData` from a bench file or a robot recording and a
spring.json; `report.py` writes Markdown, HTML, JSON, plots and the calibration JSON.
"""

from seadesign.loop.candidates import CANDIDATES, LIBRARY, Candidate
from seadesign.loop.engine import Explanation, Step, TraceEntry, explain
from seadesign.loop.fit import Fit, fit, predict
from seadesign.loop.metrics import metrics, split_metrics
from seadesign.loop.table import ROLES, LoopData, LoopInputError, from_frame, time_blocks
from seadesign.loop.whiteness import residual_tests

__all__ = [
    "CANDIDATES", "LIBRARY", "ROLES", "Candidate", "Explanation", "Fit", "LoopData", "LoopInputError", "Step",
    "TraceEntry", "explain", "fit", "from_frame", "metrics", "predict", "residual_tests", "split_metrics",
    "time_blocks",
]
