"""Stochastic oil price model (SOPM) of thesis Eq. 4.12: a geometric random walk with drift.

    S(t_k) = S0 exp(W_k),   W_{k+1} = W_k + α ξ_k + μ,   W_0 = 0,   ξ_k iid N(0, 1)

so that log S(t_k) ~ N(log S0 + μ k, α² k) after k steps. The thesis uses S0 = 75 $/bbl, α = 1e-4 and μ = ±1e-5
(Fig. 4.6) but does not state the length of one step. Read literally, W is indexed like the yearly cash flows of
Eq. 4.7 (t_{j+1} - t_j = 1 year); then the price moves by about 1e-4 over the 13-year project and the two drift cases
would be indistinguishable. We therefore make the step length explicit: ``steps_per_year`` random-walk steps per
year, default 365 (one step per day, the sampling of a daily price series). With daily steps μ = ±1e-5 is a drift
of ±0.37 %/year (75 → 78.6 or 71.5 $/bbl after 13 years in the median) and α = 1e-4 a volatility of 0.19 %/√year.
The price that enters the revenue of year j (Eq. 4.11) is S at the end of that year, t_j = j years.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from spflow.core.errors import ParameterError
from spflow.plugins.forward.checks import check_number

__all__ = ["OilPriceModel"]

_MAX_STEPS_PER_YEAR = 1_000_000


@dataclass(frozen=True)
class OilPriceModel:
    """Eq. 4.12 with initial price ``s0`` [$/bbl], volatility ``alpha`` [per √step], drift ``mu`` [per step] and
    ``steps_per_year`` random-walk steps per year (the time unit of α and μ; see the module docstring)."""

    s0: float = 75.0
    alpha: float = 1.0e-4
    mu: float = 1.0e-5
    steps_per_year: int = 365

    def __post_init__(self):
        object.__setattr__(self, "s0", check_number("oil price field 's0' [$/bbl]", self.s0, 0.0, 1.0e4,
                                                    lower_open=True))
        object.__setattr__(self, "alpha", check_number("oil price field 'alpha' [1/sqrt(step)]", self.alpha, 0.0, 1.0))
        object.__setattr__(self, "mu", check_number("oil price field 'mu' [1/step]", self.mu, -1.0, 1.0))
        n = self.steps_per_year
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 1 <= n <= _MAX_STEPS_PER_YEAR:
            raise ParameterError(f"oil price field 'steps_per_year' must be an integer in [1, {_MAX_STEPS_PER_YEAR}],"
                                 f" got {n!r}")
        object.__setattr__(self, "steps_per_year", int(n))

    def times(self, years: int) -> np.ndarray:
        """Times t_k = k / steps_per_year [year] of the walk's points k = 0 ... years·steps_per_year."""
        return np.arange(_check_years(years) * self.steps_per_year + 1) / self.steps_per_year

    def log_paths(self, years: int, n_paths: int = 1, rng: np.random.Generator | int | None = None) -> np.ndarray:
        """W_k of ``n_paths`` independent walks (n_paths, years·steps_per_year + 1), W_0 = 0 (Eq. 4.12)."""
        steps = _check_years(years) * self.steps_per_year
        if isinstance(n_paths, bool) or not isinstance(n_paths, (int, np.integer)) or n_paths < 1:
            raise ParameterError(f"n_paths must be a positive integer, got {n_paths!r}")
        xi = np.random.default_rng(rng).standard_normal((int(n_paths), steps))
        walk = np.zeros((int(n_paths), steps + 1))
        np.cumsum(self.alpha * xi + self.mu, axis=1, out=walk[:, 1:])
        return walk

    def paths(self, years: int, n_paths: int = 1, rng: np.random.Generator | int | None = None) -> np.ndarray:
        """Prices S(t_k) = S0 exp(W_k) [$/bbl] on :meth:`times` (n_paths, years·steps_per_year + 1)."""
        return self.s0 * np.exp(self.log_paths(years, n_paths, rng))

    def annual_prices(self, years: int, n_paths: int = 1,
                      rng: np.random.Generator | int | None = None) -> np.ndarray:
        """S(t_j) at the ends of the years t_j = 1, ..., ``years`` [$/bbl] (n_paths, years): the prices of Eq. 4.11."""
        return self.paths(years, n_paths, rng)[:, self.steps_per_year::self.steps_per_year]

    @property
    def annual_log_drift(self) -> float:
        """μ · steps_per_year: the drift of log S per year."""
        return self.mu * self.steps_per_year

    @property
    def annual_log_volatility(self) -> float:
        """α · √steps_per_year: the standard deviation of the change of log S over one year."""
        return self.alpha * math.sqrt(self.steps_per_year)


def _check_years(years) -> int:
    if isinstance(years, bool) or not isinstance(years, (int, np.integer)) or not 1 <= years <= 1000:
        raise ParameterError(f"years must be an integer in [1, 1000], got {years!r}")
    return int(years)
