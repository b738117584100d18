"""Net present value of one slug design (thesis Eqs. 4.7-4.11, Table 4.2) and the core-to-field scale-up.

    NPV = Σ_{j=1}^{N_t} C_I(Δt_j) / (1 + d)^{t_j} - C_o                       (Eq. 4.7, t_j = j years)
    C_I(Δt_j) = R(Δt_j) - I(Δt_j) - T(Δt_j)                                  (Eq. 4.8)
    I(Δt_j) = m_salt(Δt_j) S_salt + m_surf(Δt_j) S_surf + m_poly(Δt_j) S_poly (Eq. 4.9)
    R(Δt_j) = S(t_j) N_p(Δt_j)                                                (Eq. 4.11)

Eq. 4.9 multiplies "mass concentrations" by prices in $/lb; we read c_k(Δt_j) S_k as the mass of chemical k injected
during year j times its price. Chemicals are charged for the chemical slugs HTDS, SP and P only (the slugs Table 4.2
lists); the water floods IWF and EWF use the field's injection brine at no chemical cost. Concentrations in ppm are
taken as mass fractions of the injected brine.

Scale-up (:class:`ScaleUp`). The thesis does not say how a 6-inch core maps onto barrels and years. We place the core's
one-dimensional displacement in a field pattern of pore volume V_p [bbl] flooded at a constant rate q [PV/year]:

* injected pore volumes PV map onto project time t = (PV - PV_start) / q [year]; the project (and its discounting)
  starts when the chemical flood starts, at PV_start = 1.0 PV, the end of the fixed IWF (oil produced by the IWF is
  before the project and earns nothing);
* oil: the simulator's ``oil_cut`` is the average oil fraction of the effluent over each output interval, so the oil
  produced between two output points is oil_cut · ΔPV pore volumes, i.e. oil_cut · ΔPV · V_p barrels; the oil of year
  j is the cumulative oil, interpolated linearly in PV, between PV_start + q (j - 1) and PV_start + q j;
* chemicals: one PV of brine weighs ρ_w V_p (ρ_w = 1000 kg/m³ by default, converted with scipy.constants), so a slug
  at c ppm injects c·1e-6 ρ_w V_p pounds per PV, spread over the years the slug spans.

Defaults: V_p = 1e5 bbl, a small pilot pattern whose revenues (≈ 0.2 PV of tertiary oil, ≈ 1.5 M$) are of the order
of Table 4.2's capital (0.2 M$) and chemical costs; q = 3.5 / 13 PV/year, so that the 13 project years span the 3.5 PV
injected after the IWF (4.5 PV in total: three slugs of at most 1.0 PV each and at least 0.5 PV of EWF).
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass, fields

import numpy as np
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.plugins.forward.checks import check_number
from spflow.plugins.forward.schedule import Schedule

__all__ = ["Economics", "ScaleUp", "CHARGED_SLUGS", "npv", "annual_oil_bbl", "annual_chemical_cost",
           "cash_inflow", "project_npv"]

#: Slugs whose chemicals are paid for (Eq. 4.9); IWF and EWF are plain injection brine.
CHARGED_SLUGS = ("HTDS", "SP", "P")


def _validated(obj, ranges: dict[str, tuple[float, float, bool]], what: str) -> None:
    """Check every field of a frozen dataclass against ``ranges`` {field: (low, high, low_open)} (in place)."""
    for f in fields(obj):
        low, high, low_open = ranges[f.name]
        value = check_number(f"{what} field {f.name!r}", getattr(obj, f.name), low, high, lower_open=low_open)
        object.__setattr__(obj, f.name, value)


@dataclass(frozen=True)
class Economics:
    """Table 4.2: capital C_o [$], chemical prices S_k [$/lb], TDE T [$/year], discount rate d [1/year] and the
    project life N_t [year]."""

    capital_usd: float = 200_000.0
    salt_usd_per_lb: float = 0.5
    surfactant_usd_per_lb: float = 5.0
    polymer_usd_per_lb: float = 2.0
    tde_usd_per_year: float = 10_000.0
    discount_rate: float = 0.20
    years: int = 13

    def __post_init__(self):
        money = (0.0, 1.0e12, False)
        price = (0.0, 1.0e4, False)
        _validated(self, {"capital_usd": money, "salt_usd_per_lb": price, "surfactant_usd_per_lb": price,
                          "polymer_usd_per_lb": price, "tde_usd_per_year": money, "discount_rate": (-1.0, 10.0, True),
                          "years": (1.0, 1000.0, False)}, "economics")
        if not float(self.years).is_integer():
            raise ParameterError(f"economics field 'years' must be a whole number of years in [1, 1000], got "
                                 f"{self.years!r}")
        object.__setattr__(self, "years", int(self.years))


@dataclass(frozen=True)
class ScaleUp:
    """Core-to-field scale-up: pattern pore volume V_p [bbl], injection rate q [PV/year], project start PV_start [PV]
    and brine density ρ_w [kg/m³] (see the module docstring)."""

    pore_volume_bbl: float = 1.0e5
    injection_rate_pv_per_year: float = 3.5 / 13.0
    start_pv: float = 1.0
    brine_density_kg_m3: float = 1000.0

    def __post_init__(self):
        _validated(self, {"pore_volume_bbl": (0.0, 1.0e12, True), "injection_rate_pv_per_year": (0.0, 100.0, True),
                          "start_pv": (0.0, 1.0e3, False), "brine_density_kg_m3": (500.0, 2000.0, False)}, "scale-up")

    def pv_at(self, years) -> np.ndarray:
        """Injected PV at project time ``years`` [year]: PV_start + q t."""
        return self.start_pv + self.injection_rate_pv_per_year * np.asarray(years, dtype=float)

    def end_pv(self, project_years: int) -> float:
        """Injected PV at the end of a project of ``project_years`` years."""
        return float(self.pv_at(project_years))

    @property
    def brine_lb_per_pv(self) -> float:
        """Mass of one field pore volume of brine [lb]: ρ_w V_p (barrel and pound from scipy.constants)."""
        import scipy.constants as const  # SciPy loads when a design is evaluated, not when the stage is listed

        return self.brine_density_kg_m3 * self.pore_volume_bbl * const.barrel / const.pound


def npv(cash_inflow: np.ndarray, discount_rate: float, capital: float) -> np.ndarray:
    """Eq. 4.7: Σ_j C_I(Δt_j) / (1 + d)^j - C_o over the last axis (years j = 1 ... N_t)."""
    flows = np.asarray(cash_inflow, dtype=float)
    factors = (1.0 + discount_rate) ** -np.arange(1, flows.shape[-1] + 1)
    return flows @ factors - capital


def _year_edges(scale: ScaleUp, years: int) -> np.ndarray:
    return scale.pv_at(np.arange(years + 1))


def annual_oil_bbl(pv: np.ndarray, oil_cut: np.ndarray, scale: ScaleUp, years: int) -> np.ndarray:
    """N_p(Δt_j) [bbl] for j = 1 ... ``years`` from a simulated ``oil_cut`` (interval averages) on the ``pv`` grid.

    Oil after the last simulated PV is zero (the flood has ended).
    """
    pv, oil_cut = np.asarray(pv, dtype=float), np.asarray(oil_cut, dtype=float)
    if pv.ndim != 1 or pv.shape != oil_cut.shape or pv.size < 2 or np.any(np.diff(pv) <= 0):
        raise ParameterError("annual_oil_bbl needs 1-D pv (strictly increasing, >= 2 points) and oil_cut of the "
                             f"same shape, got {pv.shape} and {oil_cut.shape}")
    if not np.isfinite(oil_cut).all():
        raise ParameterError("annual_oil_bbl: oil_cut has non-finite values")
    cumulative = np.concatenate([[0.0], np.cumsum(oil_cut[1:] * np.diff(pv))])
    return np.diff(np.interp(_year_edges(scale, years), pv, cumulative)) * scale.pore_volume_bbl


def annual_chemical_cost(schedule: Schedule, scale: ScaleUp, economics: Economics,
                         charged: Collection[str] = CHARGED_SLUGS) -> np.ndarray:
    """I(Δt_j) [$] of Eq. 4.9 for j = 1 ... N_t: cost of the chemicals of the ``charged`` slugs injected in year j."""
    ends = np.cumsum([s.pv for s in schedule.slugs])
    starts = ends - np.array([s.pv for s in schedule.slugs])
    usd_per_pv = np.array([
        (s.salinity_ppm * economics.salt_usd_per_lb + s.surfactant_ppm * economics.surfactant_usd_per_lb
         + s.polymer_ppm * economics.polymer_usd_per_lb) * 1.0e-6 * scale.brine_lb_per_pv
        if s.name in charged else 0.0 for s in schedule.slugs])
    edges = _year_edges(scale, economics.years)
    overlap = np.clip(np.minimum(ends[None, :], edges[1:, None]) - np.maximum(starts[None, :], edges[:-1, None]),
                      0.0, None)
    return overlap @ usd_per_pv


def cash_inflow(oil_bbl: np.ndarray, prices: np.ndarray, chemical_cost: np.ndarray,
                economics: Economics) -> np.ndarray:
    """C_I(Δt_j) = S(t_j) N_p(Δt_j) - I(Δt_j) - T (Eqs. 4.8, 4.11); ``prices`` may carry leading path axes."""
    return np.asarray(prices, dtype=float) * oil_bbl - chemical_cost - economics.tde_usd_per_year


def project_npv(response: xr.Dataset, schedule: Schedule, prices: np.ndarray, scale: ScaleUp,
                economics: Economics) -> np.ndarray:
    """NPV [$] (Eq. 4.7) of one simulated design (``response``: ``oil_cut`` on ``pv``) for the annual ``prices``
    S(t_j) [$/bbl] (..., N_t) of one or more price paths."""
    prices = np.asarray(prices, dtype=float)
    if prices.shape[-1:] != (economics.years,):
        raise ParameterError(f"project_npv: prices must end with one price per project year ({economics.years}), "
                             f"got shape {prices.shape}")
    oil = annual_oil_bbl(response["pv"].values, response["oil_cut"].values, scale, economics.years)
    flows = cash_inflow(oil, prices, annual_chemical_cost(schedule, scale, economics), economics)
    return npv(flows, economics.discount_rate, economics.capital_usd)
