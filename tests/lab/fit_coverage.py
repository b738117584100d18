"""Coverage of the lab fits' 95 % intervals over regenerated synthetic data sets (shared by the surfactant fits' tests in tests/lab/).

For each seed the synthetic table is regenerated with that seed's noise, fitted, and the truth compared with the
fit's interval (Student's t with the fit's degrees of freedom). With 20 seeds and a correct 95 % interval the count
inside is >= 16 with probability 0.984; an interval too narrow by a factor 2 (68 % coverage) passes with
probability ~0.2. The spread check compares the scatter of the estimates across seeds with the mean reported
standard error: an interval too wide by a factor 2 fails it.
"""

from __future__ import annotations

import numpy as np

from spflow.plugins.lab.fit_result import fit_interval


def coverage(make, fit, truth: dict[str, float], seeds=range(20), level: float = 0.95):
    """``(inside, spread_ratio, names)``: per parameter, the number of seeds whose interval holds the truth, and the
    ratio of the estimates' standard deviation across seeds to the mean reported standard error."""
    inside, estimates, stds, names = None, [], [], None
    for seed in seeds:
        result = fit(make(seed))
        names = [str(n) for n in result["param"].values]
        lo, hi = fit_interval(result, level)
        t = np.array([truth[n] for n in names])
        hit = (lo.values <= t) & (t <= hi.values)
        inside = hit.astype(int) if inside is None else inside + hit
        estimates.append(result["estimate"].values)
        stds.append(result["std"].values)
    spread = np.std(np.array(estimates), axis=0, ddof=1) / np.mean(np.array(stds), axis=0)
    return dict(zip(names, inside)), dict(zip(names, spread)), names
