"""Sobol sensitivity indices of each output to each design axis, computed on the surrogates.

Saltelli's sampling and estimators (SALib, first-order and total indices, seeded) over the unit cube;
each sample is snapped onto the values the axes allow before the surrogate is asked, so a discrete
axis contributes through its real values. These describe the surrogates: they are as good as the
leave-one-out errors reported beside them.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from seadesign.explore.encoding import Encoding
from seadesign.explore.models import Models

BASE_SAMPLES = 512  # Saltelli base sample size N: N (dim + 2) surrogate evaluations per output


def sobol_indices(encoding: Encoding, models: Models, columns, seed: int = 0) -> pd.DataFrame:
    """One row per (output, axis): first-order `S1`, total `ST` and their 95 % confidence half-widths
    (outputs without a fitted surrogate are left out)."""
    from SALib.analyze import sobol as analyze
    from SALib.sample import sobol as sample

    spec = {"num_vars": encoding.dim, "names": list(encoding.keys), "bounds": [[0.0, 1.0]] * encoding.dim}
    X = encoding.snap(sample.sample(spec, BASE_SAMPLES, calc_second_order=False, seed=seed))
    rows = []
    for column in columns:
        model = models.surrogates[column]
        if model.gp is None:
            continue
        y = model.predict(X)
        if np.ptp(y) == 0:
            continue
        s = analyze.analyze(spec, y, calc_second_order=False, seed=seed)
        rows += [{"output": column, "axis": key, "S1": s["S1"][i], "S1_conf": s["S1_conf"][i], "ST": s["ST"][i],
                  "ST_conf": s["ST_conf"][i]} for i, key in enumerate(encoding.keys)]
    return pd.DataFrame(rows, columns=["output", "axis", "S1", "S1_conf", "ST", "ST_conf"])
