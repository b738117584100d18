"""The two objectives of the slug-size design (thesis Eq. 4.13), one noisy realisation per call.

For a design x = (s_htds, s_sp, s_p) one realisation draws ξ = (θ, S): one parameter sample θ from the calibration
posterior (§4.6; none when no posterior is given: the simulator's Table 2.4 defaults, a deterministic model) and one
oil price path S (Eq. 4.12). It runs the simulator on the design's schedule (Eq. 4.10) and returns

    y1 = -NPV(x; ξ) / 1e6   [M$]   (Eq. 4.7, negated: both objectives are minimised)
    y2 = max_PV Δp(x; θ) / 1e3   [kPa]   (the largest pressure drop over the whole flood, IWF included)

The Bayesian optimiser fits a GP with learned noise to these draws, so E[NPV] and E[max Δp] are what it optimises
(Eq. 4.13). Randomness comes from one ``numpy.random.SeedSequence``: each evaluated row spawns its own child, and the
draws are made in the calling process, so results do not depend on the number of workers. Only the drawn parameter
values (not the whole posterior) travel to the workers.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.plugins.design.parameter_map import ParameterMap
from spflow.plugins.forward.parameters import resolve_params
from spflow.plugins.forward.schedule import Schedule
from spflow.plugins.forward.simulate import simulate

from .economics import Economics, ScaleUp, project_npv
from .oil_price import OilPriceModel
from .slug_schedule import DESIGN_VARIABLES, REFERENCE, SlugReference, slug_schedule

__all__ = ["SlugDesignProblem", "Realisations", "NoisyObjective", "OBJECTIVES", "OBJECTIVE_UNITS"]

#: Names and units of the minimised objectives (columns of Y).
OBJECTIVES = ("neg_npv", "max_dp")
OBJECTIVE_UNITS = ("1e6", "kPa")  # UDUNITS: -NPV in million US dollars (M$) is the scaled number 1e6


@dataclass(frozen=True)
class SlugDesignProblem:
    """The deterministic setting of one realisation: economics, scale-up, price model, fixed simulator overrides (the
    reference flood's core, rate and fluids), the effect strengths, the reference slugs of Eq. 4.10 and the
    simulator's resolution."""

    price: OilPriceModel = field(default_factory=OilPriceModel)
    scale: ScaleUp = field(default_factory=ScaleUp)
    economics: Economics = field(default_factory=Economics)
    fixed: Mapping[str, float] = field(default_factory=dict)
    cells: int = 100
    pv_step: float = 0.01
    reference: SlugReference = REFERENCE
    effects: Mapping[str, float] = field(default_factory=dict)

    @property
    def total_pv(self) -> float:
        """Total injected PV of every design: the end of the project life under the scale-up."""
        return self.scale.end_pv(self.economics.years)

    def schedule(self, x: Sequence[float]) -> Schedule:
        """The injection schedule of design ``x`` (Eq. 4.10), ending at :attr:`total_pv`."""
        return slug_schedule(*map(float, x), total_pv=self.total_pv, reference=self.reference)

    def response(self, x: Sequence[float], theta: Mapping[str, float]) -> xr.Dataset:
        """The simulator's Dataset for design ``x`` with parameters ``theta`` on top of :attr:`fixed`."""
        return simulate(self.schedule(x), dict(self.fixed, **theta), cells=self.cells, pv_step=self.pv_step,
                        effects=dict(self.effects))

    def outcome(self, response: xr.Dataset, x: Sequence[float], prices: np.ndarray) -> tuple[float, float, float]:
        """(-NPV [M$], max Δp [kPa], tertiary oil [PV]) of a simulated design for annual ``prices`` S(t_j)."""
        value = float(project_npv(response, self.schedule(x), prices, self.scale, self.economics))
        pv, cut = response["pv"].values, response["oil_cut"].values
        tertiary = float(np.sum((cut[1:] * np.diff(pv))[pv[1:] > self.scale.start_pv]))
        return -value / 1.0e6, float(response["dp"].max()) / 1.0e3, tertiary

    def realisation(self, x: Sequence[float], theta: Mapping[str, float],
                    prices: np.ndarray) -> tuple[float, float, float]:
        """:meth:`outcome` of one simulation: the unit of work sent to a worker."""
        return self.outcome(self.response(x, theta), x, prices)


class Realisations:
    """Draws of ξ = (θ, S): ``theta`` (n, p) posterior draws of the columns ``columns`` (``None``: no parameter
    uncertainty) and price paths of ``problem.price``. ``columns``: the posterior's parameter map
    (:class:`~spflow.plugins.design.parameter_map.ParameterMap`, which UTCHEM names each column sets), or a list of
    UTCHEM names (each column sets its own parameter)."""

    def __init__(self, problem: SlugDesignProblem, theta: np.ndarray | None = None,
                 columns: ParameterMap | Sequence[str] = ()):
        self.problem = problem
        self.columns = columns if isinstance(columns, ParameterMap) else ParameterMap.identity(columns)
        self.names = self.columns.labels
        if theta is not None:
            theta = np.asarray(theta, dtype=float)
            if theta.ndim != 2 or theta.shape[0] < 1 or theta.shape[1] != len(self.names):
                raise ParameterError(f"posterior draws theta must be (draws, {len(self.names)}) for parameters "
                                     f"{list(self.names)}, got shape {theta.shape}")
            if not np.isfinite(theta).all():
                raise ParameterError("posterior draws theta contain non-finite values")
            for row in theta[[0, -1]]:  # names and values: the simulator's own validation, before any run
                resolve_params(dict(problem.fixed, **self.parameters(row)))
        else:
            resolve_params(dict(problem.fixed))
        self.theta = theta

    def parameters(self, row: np.ndarray) -> dict[str, float]:
        """UTCHEM name -> value of one posterior draw (through the parameter map)."""
        return self.columns.forward_params(row)

    def draw(self, seed: np.random.SeedSequence) -> tuple[int, dict[str, float], np.ndarray]:
        """One ξ: posterior draw index (-1 without a posterior), its parameters and the annual prices S(t_j) (N_t,)."""
        rng = np.random.default_rng(seed)
        index = -1 if self.theta is None else int(rng.integers(self.theta.shape[0]))
        theta = {} if index < 0 else self.parameters(self.theta[index])
        return index, theta, self.problem.price.annual_prices(self.problem.economics.years, 1, rng)[0]


def _check_rows(X) -> np.ndarray:
    X = np.atleast_2d(np.asarray(X, dtype=float))
    if X.ndim != 2 or X.shape[1] != len(DESIGN_VARIABLES):
        raise ParameterError(f"design rows must be (q, {len(DESIGN_VARIABLES)}) slug sizes {list(DESIGN_VARIABLES)}, "
                             f"got shape {X.shape}")
    return X


class NoisyObjective:
    """Callable X (q, 3) -> Y (q, 2) of one realisation per row, run over the rows with a joblib ``parallel``.

    Every evaluation is also logged (``log``: design, objectives, posterior draw index, tertiary oil, mean price) so
    that the stage can report the draws behind each noisy value.
    """

    def __init__(self, realisations: Realisations, parallel, seed: int):
        self.realisations = realisations
        self.parallel = parallel
        self._seeds = np.random.SeedSequence(seed)
        self.log: list[dict] = []

    def __call__(self, X) -> np.ndarray:
        from joblib import delayed  # loads when a design is evaluated, not when the stage is listed

        X = _check_rows(X)
        problem = self.realisations.problem
        for row in X:  # every slug size validated before any simulation
            problem.schedule(row)
        draws = [self.realisations.draw(s) for s in self._seeds.spawn(X.shape[0])]
        out = self.parallel(delayed(problem.realisation)(x, theta, prices) for x, (_, theta, prices) in zip(X, draws))
        out = np.asarray(out, dtype=float)
        for x, (index, _, prices), (y1, y2, oil) in zip(X, draws, out):
            self.log.append({"x": x.copy(), "y": np.array([y1, y2]), "draw": index, "oil_pv": oil,
                             "mean_price": float(np.mean(prices))})
        return out[:, :2]
