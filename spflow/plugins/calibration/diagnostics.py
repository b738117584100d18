"""Convergence diagnostics of MCMC draws (thesis appendices C and E): autocorrelation, Geweke z-scores with spectral
variance, and ArviZ's rank-normalised split R-hat and bulk/tail ESS.

**Geweke (App. E, Eq. E.1).** z = (θ̄_A − θ̄_B) / sqrt(Ŝ(0) (1/n_A + 1/n_B)) with A the first ``first`` = 10 % and
B the last ``last`` = 50 % of a chain. Ŝ(0) is the spectral density at frequency zero, Ŝ(0) = τ_int · s² (τ_int the
integrated autocorrelation time from emcee's Sokal-windowed estimator, s² the variance), so the denominator is the
Monte Carlo standard error of the difference of two segment means of a correlated chain (Geweke 1992;
docs/calibration.md, Diagnostics). The thesis's Eq. E.1 and the old PyMC3 ``geweke`` used plain variances, which
ignore the autocorrelation and
inflate |z| by about sqrt(τ_int). Ŝ(0) — τ_int and s² alike — is estimated once on the whole chain: under the null
hypothesis (stationarity) both segments share it, and estimated on a 10 % segment only a few τ long both factors are
biased low. On AR(1) chains of 888 draws (φ = 0.9, τ = 19, the length of an emcee walker-mean series at the thesis
budget) per-segment τ gave z with a spread of 1.7-2.1, per-segment s² (whole-chain τ) 1.19, the whole-chain Ŝ(0)
1.05; with 9 such z per posterior the probability that all |z| < 2 was 0.43, against 0.64 and the nominal
(2Φ(2) − 1)^9 = 0.658 (``tests/calibration/test_mcmc_geweke_calibration.py``). Several chains of the same target
are treated as replicas: their segment means are averaged, the variance of that average is τ s² (1/n_A + 1/n_B) /
chains with the autocorrelation function and s² averaged over chains.

**Reading k z-scores at once** (:func:`geweke_familywise`). Under convergence the k z-scores of one posterior (one
per parameter) are approximately jointly normal with unit variances. "All |z| < 2" then holds with probability
(2Φ(2) − 1)^k if they are independent (0.658 for k = 9), and by Šidák's inequality at least that for any correlation
between them: a converged sampler fails that criterion on about one run in three. Family-wise readings with a stated
false-alarm rate: the Šidák p-value of max|z|, 1 − (2Φ(max|z|) − 1)^k (exact for independent z, conservative
otherwise), and the Bonferroni level Φ⁻¹(1 − α/(2k)) (2.77 for k = 9, α = 0.05).

For emcee, whose walkers within one run are correlated through the ensemble moves, the Geweke test is applied to
each run's walker-mean series (a function of the ensemble's Markov state, so its spectral variance includes the
cross-walker correlation), the runs being the replicas (:func:`independent_series`).

**R-hat / ESS** come from ArviZ (``az.rhat`` rank-normalised split R-hat, ``az.ess`` bulk and tail; Vehtari et al.
2021), imported only when a summary is computed (:func:`arviz`).
"""

from __future__ import annotations

import warnings

import emcee
import numpy as np
import xarray as xr
from scipy.stats import norm

from spflow.core.cf_metadata import UNITS_VARIABLE
from spflow.core.errors import ParameterError

__all__ = ["arviz", "integrated_time", "geweke", "geweke_familywise", "geweke_intervals", "autocorrelation",
           "independent_series", "summary"]


def arviz():
    """The ``arviz`` module, imported here, when a computation needs it, rather than when spflow is imported.

    ``import arviz`` costs about 1.5 s (it imports ``matplotlib.pyplot``) and ArviZ 0.2x announces its 1.0 refactor
    with a ``FutureWarning`` on import. ArviZ 1.x, which has no such notice, needs Python >= 3.12 while spflow
    supports 3.10 and pins ``arviz<1``; the functions used here (``rhat``, ``ess``, ``loo``, ``from_dict``) keep
    their meaning in 1.x. So this one notice, matched by its text, is the only warning silenced, at the one place
    spflow imports ArviZ; any other warning ArviZ's import raises passes through."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=r"\s*ArviZ is undergoing a major refactor", category=FutureWarning)
        import arviz as az
    return az


def _chains(x: np.ndarray) -> np.ndarray:
    """``x`` as (chain, draw): a 1-D series is one chain."""
    x = np.asarray(x, dtype=float)
    if x.ndim == 1:
        x = x[None, :]
    if x.ndim != 2 or x.shape[1] < 4:
        raise ParameterError(f"MCMC diagnostics need draws of shape (chain, draw) with >= 4 draws, got {x.shape}")
    return x


def integrated_time(x: np.ndarray) -> float:
    """τ_int of draws (chain, draw): emcee's Sokal-windowed estimate (c = 5) on the chain-averaged autocorrelation.

    No length check is made (emcee's ``tol``); a short chain gives a lower bound, which ESS reports separately."""
    x = _chains(x)
    return float(emcee.autocorr.integrated_time(x.T[:, :, None], c=5, tol=0)[0])


def geweke(x: np.ndarray, first: float = 0.1, last: float = 0.5) -> float:
    """Geweke's z of draws (chain, draw) (or one chain (draw,)) with spectral variances (module docstring)."""
    if not (0 < first < 1 and 0 < last < 1 and first + last <= 1):
        raise ParameterError(f"Geweke segments: need 0 < first, last < 1 and first + last <= 1, got {first}, {last}")
    x = _chains(x)
    n = x.shape[1]
    a, b = x[:, : max(int(first * n), 4)], x[:, n - max(int(last * n), 4):]
    spectral_zero = integrated_time(x) * np.mean(np.var(x, axis=1))  # Ŝ(0) of the whole chain
    se2 = spectral_zero * (1.0 / a.shape[1] + 1.0 / b.shape[1]) / x.shape[0]
    return float((a.mean() - b.mean()) / np.sqrt(se2))


def geweke_familywise(z: np.ndarray, alpha: float = 0.05) -> dict[str, float]:
    """Family-wise reading of the k Geweke z-scores of one posterior (module docstring), alongside — not instead
    of — the per-parameter z: ``max_abs_z``; ``p_max`` = 1 − (2Φ(max|z|) − 1)^k, the Šidák p-value of the largest
    |z| under convergence; ``bonferroni_z`` = Φ⁻¹(1 − α/(2k)), the level every |z| of a converged sampler stays
    below with probability >= 1 − α; ``p_all_below_2`` = (2Φ(2) − 1)^k, the probability that a converged sampler
    meets "all |z| < 2" when the z are independent (a lower bound otherwise)."""
    z = np.asarray(z, dtype=float).ravel()
    if not z.size or not np.isfinite(z).all():
        raise ParameterError(f"geweke_familywise: need finite z-scores, got {z.tolist()}")
    if not 0 < alpha < 1:
        raise ParameterError(f"geweke_familywise: alpha must lie in (0, 1), got {alpha}")
    k, top = z.size, float(np.max(np.abs(z)))
    return {"max_abs_z": top, "p_max": float(-np.expm1(k * np.log1p(-2.0 * norm.sf(top)))),
            "bonferroni_z": float(norm.isf(alpha / (2 * k))), "p_all_below_2": float((1 - 2 * norm.sf(2.0)) ** k)}


def geweke_intervals(x: np.ndarray, first: float = 0.1, last: float = 0.5,
                     intervals: int = 20) -> tuple[np.ndarray, np.ndarray]:
    """z-scores of sub-chains starting at ``intervals`` points of the first half (the App. E plot): (starts, z)."""
    x = _chains(x)
    starts = np.linspace(0, x.shape[1] // 2, intervals).astype(int)
    return starts, np.array([geweke(x[:, s:], first, last) for s in starts])


def autocorrelation(x: np.ndarray, max_lag: int = 100) -> np.ndarray:
    """Autocorrelation ρ_k (Eq. C.1) for k = 0..max_lag, averaged over chains (emcee's FFT estimator)."""
    x = _chains(x)
    acf = np.mean([emcee.autocorr.function_1d(chain) for chain in x], axis=0)
    return acf[: max_lag + 1]


def independent_series(posterior: xr.Dataset, variable: str = "theta", dim: str = "param") -> np.ndarray:
    """Draws (series, draw, dim) of independent Markov chains: the chains themselves, or for emcee output (chains
    labelled by ``chain_run``) the walker mean of each run."""
    da = posterior[variable].transpose("chain", "draw", dim)
    if "chain_run" in posterior.coords:
        da = da.groupby(posterior["chain_run"]).mean("chain").rename(chain_run="chain").transpose("chain", "draw", dim)
    return da.values


def summary(posterior: xr.Dataset, variable: str = "theta", dim: str = "param") -> xr.Dataset:
    """Per ``dim`` entry of ``posterior[variable]`` (chain, draw, dim): mean, sd, 2.5/50/97.5 % quantiles, R-hat,
    bulk and tail ESS, τ_int (walker- or chain-averaged autocorrelation) and the Geweke z of the independent series;
    the family-wise reading of the z-scores (:func:`geweke_familywise`, α = 0.05) as attrs ``geweke_*``."""
    az = arviz()
    da = posterior[variable].transpose("chain", "draw", dim)
    sub = xr.Dataset({variable: da})
    values = da.values
    series = independent_series(posterior, variable, dim)
    out = xr.Dataset(
        {
            "mean": (dim, values.mean(axis=(0, 1))),
            "sd": (dim, values.std(axis=(0, 1), ddof=1)),
            "q025": (dim, np.quantile(values, 0.025, axis=(0, 1))),
            "q500": (dim, np.quantile(values, 0.5, axis=(0, 1))),
            "q975": (dim, np.quantile(values, 0.975, axis=(0, 1))),
            "rhat": (dim, az.rhat(sub)[variable].values),
            "ess_bulk": (dim, az.ess(sub, method="bulk")[variable].values),
            "ess_tail": (dim, az.ess(sub, method="tail")[variable].values),
            "tau_int": (dim, [integrated_time(values[:, :, k]) for k in range(values.shape[2])]),
            "geweke_z": (dim, [geweke(series[:, :, k]) for k in range(values.shape[2])]),
        },
        coords={dim: da[dim].values},
    )
    # the statistics of the draws are in the draws' units (one, or per element: the unit variable comes along)
    same = {k: da.attrs[k] for k in ("units", UNITS_VARIABLE) if k in da.attrs}
    if same.get(UNITS_VARIABLE) in posterior.variables:
        out[same[UNITS_VARIABLE]] = posterior[same[UNITS_VARIABLE]]
    else:
        same.pop(UNITS_VARIABLE, None)
    names = {"mean": "posterior mean", "sd": "posterior standard deviation", "q025": "2.5 % posterior quantile",
             "q500": "posterior median", "q975": "97.5 % posterior quantile", "rhat": "rank-normalised split R-hat",
             "ess_bulk": "bulk effective sample size", "ess_tail": "tail effective sample size",
             "tau_int": "integrated autocorrelation time, in kept draws", "geweke_z": "Geweke z-score"}
    for name, long_name in names.items():
        out[name].attrs = dict(same if name in ("mean", "sd", "q025", "q500", "q975") else {"units": "1"},
                               long_name=long_name)
    out.attrs.update({f"geweke_{k}": v for k, v in geweke_familywise(out["geweke_z"].values).items()})
    return out
