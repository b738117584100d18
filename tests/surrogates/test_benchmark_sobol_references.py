"""The closed-form Sobol indices that benchmarks/bench_surrogates_peers.py scores the surrogates against
(benchmarks/analytic_functions.py) against a Monte Carlo estimate computed here, and against the published Ishigami
values."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

_PATH = Path(__file__).resolve().parents[2] / "benchmarks" / "analytic_functions.py"
_SPEC = importlib.util.spec_from_file_location("analytic_functions", _PATH)
analytic = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(analytic)


def _jansen(func, lower, upper, n, batches, seed):
    """Plain Monte Carlo, pick-freeze with A_B^(i) (A with column i from B), Jansen (1999) estimators:
    S_i = 1 - E[(f(B) - f(A_B^i))^2] / (2V), S_Ti = E[(f(A) - f(A_B^i))^2] / (2V). Returns the mean of ``batches``
    independent estimates of n base points each and the standard error of that mean, for S and S_T, each (d,)."""
    rng = np.random.default_rng(seed)
    d = lower.size
    first, total = [], []
    for _ in range(batches):
        a = lower + (upper - lower) * rng.random((n, d))
        b = lower + (upper - lower) * rng.random((n, d))
        fa, fb = func(a), func(b)
        variance = np.var(np.concatenate([fa, fb]))
        s, st = np.empty(d), np.empty(d)
        for i in range(d):
            ab = a.copy()
            ab[:, i] = b[:, i]
            fab = func(ab)
            s[i] = 1.0 - np.mean((fb - fab) ** 2) / (2.0 * variance)
            st[i] = np.mean((fa - fab) ** 2) / (2.0 * variance)
        first.append(s)
        total.append(st)
    first, total = np.array(first), np.array(total)
    se = [x.std(axis=0, ddof=1) / np.sqrt(batches) for x in (first, total)]
    return first.mean(axis=0), total.mean(axis=0), se[0], se[1]


@pytest.mark.parametrize("problem", ["ishigami", "g_function"])
def test_closed_form_indices_match_monte_carlo(problem):
    func, lower, upper = analytic.PROBLEMS[problem]
    first, total = analytic.CLOSED_FORM_SOBOL[problem]()
    mc_first, mc_total, se_first, se_total = _jansen(func, lower, upper, n=8192, batches=24, seed=11)
    assert first.shape == total.shape == (lower.size,)
    # 4.5 standard errors: a false alarm at < 1e-4 per index; every index checked, first and total
    assert np.all(np.abs(first - mc_first) < 4.5 * se_first), (first, mc_first, se_first)
    assert np.all(np.abs(total - mc_total) < 4.5 * se_total), (total, mc_total, se_total)
    # the resolution is fine enough to tell the indices apart (else the check above could not fail)
    assert se_first.max() < 0.01 and se_total.max() < 0.01


def test_ishigami_indices_equal_the_published_values():
    # a = 7, b = 0.1: S = (0.3139, 0.4424, 0), S_T = (0.5576, 0.4424, 0.2437), the values quoted in the PCE literature
    # (e.g. Sudret 2008, Reliab. Eng. Syst. Saf. 93, 964-979)
    first, total = analytic.ishigami_sobol()
    np.testing.assert_allclose(first, [0.3139, 0.4424, 0.0], atol=1e-4)
    np.testing.assert_allclose(total, [0.5576, 0.4424, 0.2437], atol=1e-4)

