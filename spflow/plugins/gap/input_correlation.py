"""Residual/input cross-correlation: does the misfit follow an injected channel, and with which lag (the
system-identification residual test, Ljung 1999 §16.6; docs/gap.md, Method: **Where**)?

The system-identification test of unmodelled dynamics (Ljung 1999 §16.6; MATLAB ``resid``): residuals that
correlate with an input at a positive lag point to a mechanism driven by that input -- with salinity steps to
salinity-dependent viscosity or phase behaviour, with the polymer front to IPV, retention or kinetics, with the
surfactant slug to surfactant retention or desaturation, with rate steps to a rate-dependent mechanism (shear
thinning or thickening, rate-dependent trapping: the in-situ rheology floods labs run). The channels are the
injected schedule's per-slug ``salinity_ppm``, ``surfactant_ppm`` and ``polymer_ppm`` (Table 2.5) and the injection
rate ``rate_ml_min`` (a slug's own rate, else the run's ``QINJ``, which the caller passes per coreflood) at each PV,
lagged by ``0, pv_step, ..., max_lag`` PV (before injection started a channel holds its first slug's value). A
channel that is constant over a block at every lag (e.g. salinity in BCF1, the rate of a coreflood without rate
steps) is not testable and is left out.

**Statistic.** Per (variable, experiment) block with error model ``W`` (the AR(1) whitening of
:mod:`~spflow.plugins.gap.error_model`) and whitened residuals ``w = W e``, the residual is regressed on each lagged
channel ``x_l`` by generalised least squares under that same AR(1) model, with an intercept (the block's bias is
not an input effect): with ``a_l`` the part of ``W x_l`` orthogonal to ``W 1``,

    z_l = a_l' w / (||a_l|| s_l),   beta_l = a_l' w / ||a_l||^2   (variable units per channel unit),
    s_l^2 = max(1, RSS_l / (n - 2)),

``RSS_l`` the residual sum of squares of the regression on (intercept, channel). This is the prewhitened
cross-correlation (Box & Jenkins): whitening the input with the residual's own AR(1) filter makes ``z_l`` the
matched-filter (GLS t) statistic. The scale ``s_l`` is the error model's (1) unless the residual scatter is larger
(a misfit that merely scatters more than the noise is then not credited to the channel). Per channel the test
statistic is ``Z = max_l |z_l|``; since ``w`` is iid N(0, 1) under the model and the channel is fixed, its null
distribution depends only on the lagged regressors and is drawn by Monte Carlo with iid normal ``w`` (exact,
``(1 + count) / (draws + 1)``), whatever the input's autocorrelation.
The diagnosis flags a (block, channel) pair when its p-value passes a Bonferroni test at ``alpha`` over all pairs.
The effect size is ``beta`` at the best lag times the channel's range: the residual change (variable units) that
goes with the channel's step.
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np

from spflow.core.errors import ParameterError

from .error_model import BlockErrorModel
from .layout import Layout
from .observed import Experiment

__all__ = ["CHANNELS", "InputCorrelation", "channel_series", "lagged", "lag_scan", "input_correlations"]

#: input channels of a schedule (slug fields: concentrations in ppm, the injection rate in ml/min)
CHANNELS = ("salinity_ppm", "surfactant_ppm", "polymer_ppm", "rate_ml_min")
_RELATIVE_TOL = 1e-9


def channel_series(exp: Experiment, channel: str, pv: np.ndarray, qinj: float) -> np.ndarray:
    """The injected value of ``channel`` (a :class:`~spflow.plugins.forward.schedule.Slug` field) at injected pore
    volumes ``pv`` (before 0 PV: the first slug's value); ``qinj`` is the run's QINJ (ml/min), the rate of the slugs
    that set none."""
    if channel not in CHANNELS:
        raise ParameterError(f"input channel {channel!r} is unknown; allowed {list(CHANNELS)}")
    if channel == "rate_ml_min":
        values = exp.schedule.rates_ml_min(qinj)
    else:
        values = np.array([getattr(s, channel) for s in exp.schedule.slugs])
    return values[exp.slug_index(np.maximum(np.asarray(pv, dtype=float), 0.0))]


def lagged(exp: Experiment, channel: str, pv: np.ndarray, lags: np.ndarray, qinj: float) -> np.ndarray:
    """(n, L) matrix of the channel at ``pv - lag`` for every lag (PV); ``qinj`` as in :func:`channel_series`."""
    return np.stack([channel_series(exp, channel, np.asarray(pv) - lag, qinj) for lag in lags], axis=1)


@dataclass(frozen=True)
class _Regressors:
    """The whitened lagged channel of one block: unit columns ``u`` (n, lags that vary) orthogonal to the whitened
    intercept, the unit intercept ``c``, which lags vary (``ok``) and the columns' norms before scaling."""

    u: np.ndarray
    c: np.ndarray
    ok: np.ndarray
    norm: np.ndarray

    def scan(self, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """z (lags, ...) and the raw projections of residual columns ``v`` (n, ...)."""
        proj = np.tensordot(self.u, v, axes=(0, 0))
        rss = np.sum(v * v, axis=0) - np.tensordot(self.c, v, axes=(0, 0)) ** 2 - proj**2
        return proj / np.sqrt(np.maximum(rss / (self.c.size - 2), 1.0)), proj

    def null(self, draws: int, rng: np.random.Generator) -> np.ndarray:
        """Monte Carlo draws of max |z| for iid N(0, 1) residuals."""
        return np.abs(self.scan(rng.standard_normal((self.c.size, draws)))[0]).max(axis=0)


def _regressors(noise: BlockErrorModel, x: np.ndarray) -> _Regressors | None:
    ones = noise.whiten(np.ones(x.shape[0]))
    a = noise.whiten(np.asarray(x, dtype=float))
    a = a - np.outer(ones, ones @ a) / (ones @ ones)
    norm = np.linalg.norm(a, axis=0)
    scale = np.linalg.norm(noise.whiten(x), axis=0)
    ok = norm > _RELATIVE_TOL * np.maximum(scale, 1e-300)
    if not ok.any():
        return None
    return _Regressors(a[:, ok] / norm[ok], ones / np.linalg.norm(ones), ok, norm)


def _scan(w: np.ndarray, r: _Regressors, null: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    z, beta = np.full(r.ok.size, np.nan), np.full(r.ok.size, np.nan)
    z[r.ok], proj = r.scan(w)
    beta[r.ok] = proj / r.norm[r.ok]
    stat = float(np.max(np.abs(z[r.ok])))
    return z, beta, float((1 + np.sum(null >= stat)) / (null.size + 1))


def lag_scan(w: np.ndarray, noise: BlockErrorModel, x: np.ndarray, draws: int, rng: np.random.Generator,
             ) -> tuple[np.ndarray, np.ndarray, float] | None:
    """(z_l, beta_l, p-value of max |z_l|) of whitened residuals ``w`` against the lagged channel columns ``x``
    (n, L) under the AR(1) error model ``noise`` (module docstring); None when no lag varies over the block."""
    r = _regressors(noise, x)
    return None if r is None else _scan(w, r, r.null(draws, rng))


#: null draws of the last few scanned layouts (a diagnosis scans the same layout for its base and final model)
_NULLS: OrderedDict[bytes, list[np.ndarray]] = OrderedDict()
_NULLS_KEPT = 2


@dataclass(frozen=True)
class InputCorrelation:
    """The lag scan of one (variable, experiment, channel): z and beta per lag, the best lag and its effect."""

    variable: str
    experiment: str
    channel: str
    lags: np.ndarray
    z: np.ndarray
    beta: np.ndarray
    pvalue: float
    channel_range: float
    significant: bool = False

    @property
    def best(self) -> int:
        return int(np.nanargmax(np.abs(self.z)))

    @property
    def lag(self) -> float:
        return float(self.lags[self.best])

    @property
    def statistic(self) -> float:
        return float(np.abs(self.z[self.best]))

    @property
    def effect(self) -> float:
        """Residual change (variable units) that goes with the channel's full step at the best lag."""
        return float(self.beta[self.best] * self.channel_range)


def input_correlations(layout: Layout, whitened: np.ndarray, experiments: list[Experiment], qinj: dict[str, float],
                       alpha: float, max_lag: float, pv_step: float, draws: int = 20000, seed: int = 0,
                       reuse: bool = True) -> list[InputCorrelation]:
    """Lag scans of every testable (block, channel) of ``layout``, flagged at Bonferroni level ``alpha`` over all of
    them; most significant (then largest statistic) first. ``qinj``: each experiment's run QINJ (ml/min), the rate of
    its slugs that set none. ``reuse``: take the null draws of an earlier scan of the same layout (same results, less
    CPU); ``False`` draws them afresh and keeps nothing."""
    if not max_lag >= 0.0:
        raise ParameterError(f"max_lag = {max_lag!r} PV is out of range; allowed [0, inf)")
    lags = np.arange(int(np.floor(max_lag / pv_step + 1e-9)) + 1) * pv_step
    by_name = {e.name: e for e in experiments}
    tests = []
    for block, s in zip(layout.blocks, layout.slices()):
        for channel in CHANNELS:
            x = lagged(by_name[block.experiment], channel, block.pv, lags, qinj[block.experiment])
            r = _regressors(block.noise, x)
            if r is not None:
                tests.append((block, s, channel, x, r))
    # the null draws depend on the regressors, the seed and the number of draws only (not on the residuals):
    # drawn in the same order as scan by scan, and reused when the same layout is scanned again
    digest = hashlib.sha256(np.array([seed, draws], dtype=np.int64).tobytes())
    for *_, r in tests:
        digest.update(r.u.tobytes())
        digest.update(r.c.tobytes())
    key = digest.digest()
    if reuse and key in _NULLS:
        nulls = _NULLS[key]
    else:
        rng = np.random.default_rng(seed)
        nulls = [r.null(draws, rng) for *_, r in tests]
        if reuse:
            _NULLS[key] = nulls
            while len(_NULLS) > _NULLS_KEPT:
                _NULLS.popitem(last=False)
    out = [InputCorrelation(block.variable, block.experiment, channel, lags, *_scan(whitened[s], r, null),
                            float(np.ptp(x)))
           for (block, s, channel, x, r), null in zip(tests, nulls)]
    level = alpha / max(len(out), 1)
    out = [InputCorrelation(c.variable, c.experiment, c.channel, c.lags, c.z, c.beta, c.pvalue, c.channel_range,
                            c.pvalue < level) for c in out]
    return sorted(out, key=lambda c: (c.pvalue, -c.statistic))
