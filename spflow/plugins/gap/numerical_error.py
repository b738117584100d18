"""The simulator's own numerical error on the data's grid, as part of every candidate's error model (issue 20).

Twins made by the model's own numerics share its discretisation error with the model; real corefloods (or data
from another simulator) do not. A front that the base model puts 0.02 PV too early because of its grid is then a
"gap" -- and the catalogue effect that moves fronts most alike gets the credit. The diagnosis therefore measures
the size of its own numerical error where the data are: the calibrated base model is run again under other,
equally legitimate numerics (by default twice the cells with the same scheme -- the Richardson pair of the grid
-- and twice the cells with first-order upwind transport, a scheme with a different truncation error) and the
spread

    d_i = max_v |y_v,i - y_i|       (widened by a running maximum over ``window`` neighbouring grid points,
                                     because a front moved by the numerics moves its error peak too)

is the shape of the numerical error at point ``i``. It enters the error model of every block as an independent
term added to the measurement variance: each AR(1) scale ``a_i`` becomes ``sqrt(a_i^2 + s^2 d_i^2)`` (for an
integrated block, the random-walk innovation, the increments of ``d``), with the factor ``s`` estimated from the
base model's calibration residuals (:mod:`~spflow.plugins.gap.numerical_scale`: about 0 for data that share the
model's numerics, about 1 or more for data from other numerics). Every model then -- base, candidates,
competitors -- is judged with the same covariance: a misfit of the size of the simulator's own numerical error is
no longer evidence of a missing mechanism (docs/gap.md, Method: **Numerical error**;
the numerical error as a part of the likelihood covariance, as in Kennedy & O'Hagan 2001).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import maximum_filter1d

from spflow.core.errors import SpflowError

from .error_model import BlockErrorModel
from .layout import Block, Layout
from .least_squares import Fit
from .prediction import Predictor

__all__ = ["Numerics", "DEFAULT_VARIANTS", "NumericalSpread", "NumericalTerm", "numerical_spread", "inflate"]


@dataclass(frozen=True)
class Numerics:
    """Alternative numerics of a forward run: the base model's cells times ``refine`` and transport ``scheme``
    (``None``: the base model's own)."""

    refine: int = 2
    scheme: str | None = None

    def label(self, base) -> str:
        return f"{self.refine * base.cells} cells, {self.scheme or base.scheme}"


#: the default variants: the grid's Richardson partner, and first-order upwind on it
DEFAULT_VARIANTS = (Numerics(2, None), Numerics(2, "upwind"))


@dataclass(frozen=True)
class NumericalSpread:
    """Per (variable, experiment): the spread ``d`` on the experiment's grid (NaN where not predicted), the
    variants' labels, the forward runs spent and their CPU seconds."""

    series: dict[tuple[str, str], np.ndarray]
    variants: list[str]
    runs: int
    run_cpu: float = 0.0

    def rms(self, layout: Layout) -> dict[tuple[str, str], float]:
        """Root-mean-square spread of every block of ``layout`` (in the variable's units)."""
        return {(b.variable, b.experiment): float(np.sqrt(np.mean(self.series[(b.variable, b.experiment)][b.index]
                                                                  ** 2)))
                for b in layout.blocks if (b.variable, b.experiment) in self.series}


def numerical_spread(predictor: Predictor, fitted: Fit, variants: Sequence[Numerics], window: int = 3,
                     ) -> NumericalSpread:
    """The spread of the predictions at ``fitted`` over ``variants`` (module docstring), for every experiment and
    observed variable of ``predictor``."""
    names = sorted(predictor.experiments)
    point = [fitted.point]
    reference = predictor.predict(point, names)[0]
    if reference is None:
        raise SpflowError("the forward run at the calibrated base point failed")
    spread: dict[tuple[str, str], np.ndarray] = {}
    labels, runs, cpu = [], 0, 0.0
    for v in variants:
        base = dataclasses.replace(predictor.base, cells=v.refine * predictor.base.cells,
                                   scheme=v.scheme or predictor.base.scheme)
        other = Predictor(base, list(predictor.experiments.values()), predictor.parallel)
        alt = other.predict(point, names)[0]
        runs += other.runs
        cpu += other.run_cpu
        labels.append(v.label(predictor.base))
        if alt is None:
            raise SpflowError(f"the forward run of the calibrated base model with {v.label(predictor.base)} failed")
        for exp in names:
            for variable, series in reference[exp].items():
                d = np.abs(np.asarray(alt[exp][variable]) - np.asarray(series))
                key = (variable, exp)
                spread[key] = d if key not in spread else np.fmax(spread[key], d)
    if window > 1:
        spread = {k: _widen(d, window) for k, d in spread.items()}
    return NumericalSpread(spread, labels, runs, cpu)


def _widen(d: np.ndarray, window: int) -> np.ndarray:
    finite = np.isfinite(d)
    out = maximum_filter1d(np.where(finite, d, 0.0), size=window, mode="nearest")
    return np.where(finite, out, np.nan)


def inflate(layout: Layout, spread: Mapping[tuple[str, str], np.ndarray], factor: float = 1.0) -> Layout:
    """``layout`` with the numerical-error scale ``factor * d`` added to every block's error model (module
    docstring); blocks without a spread keep theirs."""
    blocks = []
    for b in layout.blocks:
        d = spread.get((b.variable, b.experiment))
        if d is None:
            blocks.append(b)
            continue
        d = factor * np.nan_to_num(np.asarray(d, float)[b.index])
        if b.noise.integrated:
            d = np.abs(np.diff(d, prepend=0.0))
        noise = BlockErrorModel(np.sqrt(b.noise.scale**2 + d**2), b.noise.phi)
        blocks.append(Block(b.variable, b.experiment, b.index, b.pv, b.observed, b.slug, noise))
    return Layout(tuple(blocks))


@dataclass(frozen=True)
class NumericalTerm:
    """A diagnosis's numerical-error term, carried to experiments it has not seen (e.g. a proposed next coreflood):
    the calibrated base point the spread is measured at, the alternative numerics, the widening window and the
    estimated scale ``s`` (:mod:`~spflow.plugins.gap.numerical_scale`)."""

    fit: Fit
    variants: tuple[Numerics, ...]
    scale: float
    window: int = 3

    def spread(self, predictor: Predictor) -> NumericalSpread:
        """The spread on ``predictor``'s experiments (a predictor of the base model the fit belongs to)."""
        return numerical_spread(predictor, self.fit, self.variants, self.window)
