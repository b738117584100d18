"""Issue #24: the corrected leave-one-out error of hybrid LARS (Blatman & Sudret 2011) against explicit refits and the
factor's formula, the degree search past the thesis's p = 5, and the warning when the selected degree is the cap."""

import warnings

import numpy as np
import pytest
from numpy.polynomial import legendre

from spflow.core.errors import DegreeCapWarning, ParameterError
from spflow.plugins.surrogates.basis import design_matrix, multi_indices
from spflow.plugins.surrogates.degree_adaptive import fit_pce
from spflow.plugins.surrogates.lars import hybrid_lars
from spflow.plugins.surrogates.outputs import OutputIndex
from spflow.plugins.surrogates.pce_model import PCE


def _corrected_loo_by_refits(psi: np.ndarray, y: np.ndarray) -> float:
    """ε*_LOO by hand: N explicit least-squares refits without point i, ε_LOO = mean(e_(i)²)/Var(y) (population
    variance), times T(P, N) = N/(N − P) · (1 + tr(C_emp⁻¹)/N) with C_emp = ΨᵀΨ/N."""
    n, p = psi.shape
    residuals = np.empty(n)
    for i in range(n):
        keep = np.arange(n) != i
        coef, *_ = np.linalg.lstsq(psi[keep], y[keep], rcond=None)
        residuals[i] = y[i] - psi[i] @ coef
    loo = np.mean(residuals**2) / np.var(y)
    c_emp = psi.T @ psi / n
    return n / (n - p) * (1.0 + np.trace(np.linalg.inv(c_emp)) / n) * loo


def _noisy_data(n=30, seed=3):
    rng = np.random.default_rng(seed)
    z = rng.uniform(-1, 1, (n, 2))
    y = np.exp(z[:, 0]) + 0.5 * z[:, 0] * z[:, 1] ** 2 + 0.05 * rng.normal(size=n)
    return z, y


def test_lars_corrected_loo_equals_explicit_refits_on_the_selected_basis():
    z, y = _noisy_data()
    psi = design_matrix(z, multi_indices(2, 4, 1.0))
    result = hybrid_lars(psi, y)
    assert 1 < result.active.size < psi.shape[1]  # a genuinely sparse selection
    assert result.modified_loo == pytest.approx(_corrected_loo_by_refits(psi[:, result.active], y), rel=1e-9)


def test_reported_error_variance_is_the_corrected_loo_of_the_selected_basis():
    z, y = _noisy_data(n=40, seed=4)
    lower, upper = np.array([0.0, 10.0]), np.array([2.0, 30.0])
    x = lower + (z + 1.0) / 2.0 * (upper - lower)
    outputs = OutputIndex(np.array(["y"]), np.array([""]), np.array([np.nan]), {"y": "1"})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DegreeCapWarning)  # whether degree 4 is the best does not matter here
        model = PCE.fit(["a", "b"], lower, upper, outputs, x, y[:, None], degree_max=4, solver="lars")
    selected = np.flatnonzero(model.coefficients[0])
    psi = design_matrix(model.to_unit(x), model.indices[selected])
    expected = _corrected_loo_by_refits(psi, y) * np.var(y)
    _, variance = model.predict(x[:3])
    np.testing.assert_allclose(variance, expected, rtol=1e-9)


def _degree_8_polynomial(z):
    """(z − 0.3)^8 / 4 + z³ − z: degree 8, with odd and even terms."""
    return (z - 0.3) ** 8 / 4.0 + z**3 - z


@pytest.mark.parametrize("solver", ["ols", "lars"])
def test_degree_search_goes_past_5_and_recovers_a_degree_8_polynomial(solver):
    z = np.linspace(-1, 1, 40)[:, None]
    with warnings.catch_warnings():
        warnings.simplefilter("error", DegreeCapWarning)  # the cap (15) is not reached
        fit = fit_pce(z, _degree_8_polynomial(z[:, 0]), solver=solver)
    assert fit.degree >= 8 and fit.cap_warning == ""
    # independent reference: the Legendre series of the polynomial, on the orthonormal P~_n = sqrt(2n + 1) P_n
    power = np.polynomial.polynomial.Polynomial([-0.3, 1.0]) ** 8 / 4.0 + np.polynomial.polynomial.Polynomial(
        [0.0, -1.0, 0.0, 1.0])
    leg = legendre.poly2leg(power.coef)
    expected = leg / np.sqrt(2.0 * np.arange(leg.size) + 1.0)
    coefficients = np.zeros(fit.degree + 1)
    coefficients[fit.indices[:, 0]] = fit.coefficients[0]
    np.testing.assert_allclose(coefficients[:9], expected, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(coefficients[9:], 0.0, atol=1e-10)
    z_new = np.random.default_rng(5).uniform(-1, 1, (200, 1))
    np.testing.assert_allclose(design_matrix(z_new, fit.indices) @ fit.coefficients[0],
                               _degree_8_polynomial(z_new[:, 0]), atol=1e-9)


def test_cap_warning_fires_when_the_selected_degree_is_degree_max():
    z = np.linspace(-1, 1, 40)[:, None]
    with pytest.warns(DegreeCapWarning, match=r"selected degree 5 .*degree_max = 5"):
        fit = fit_pce(z, _degree_8_polynomial(z[:, 0]), degree_max=5, solver="lars")
    assert fit.degree == 5 and fit.degree_cap == 5 and "degree_max = 5" in fit.cap_warning


def test_cap_warning_fires_at_the_basis_size_limit_and_is_stored():
    rng = np.random.default_rng(6)
    x = rng.uniform(0, 1, (120, 8))
    y = np.exp(1.5 * x[:, 0]) * np.cos(2 * x[:, 1]) + np.sin(3 * x[:, 2])
    outputs = OutputIndex(np.array(["y"]), np.array([""]), np.array([np.nan]), {"y": "1"})
    names = [f"x{k}" for k in range(8)]
    # one candidate term per run would be 120 terms; the limit is never below 1000 terms, so degree 4 (495 terms at
    # q = 1) is the last degree tried and degree 5 (1287 terms) is not
    with pytest.warns(DegreeCapWarning, match=r"basis-size limit: degree 5 needs 1287 candidate terms"):
        model = PCE.fit(names, np.zeros(8), np.ones(8), outputs, x, y[:, None], q=1.0, solver="lars",
                        max_terms_ratio=1.0)
    ds = model.to_dataset()
    assert model.info["degree"] == 4 and ds.attrs["degree_cap"] == 4
    assert "basis-size limit" in ds.attrs["degree_cap_warning"]


def test_no_cap_warning_when_the_search_stops_by_itself():
    z = np.random.default_rng(7).uniform(-1, 1, (60, 2))
    y = 1 + z[:, 0] * z[:, 1] - 2 * z[:, 1] ** 2 + 0.01 * np.random.default_rng(8).normal(size=60)
    with warnings.catch_warnings():
        warnings.simplefilter("error", DegreeCapWarning)
        fit = fit_pce(z, y, solver="lars")
    assert fit.degree < fit.degree_cap and fit.cap_warning == ""


def test_bad_basis_size_ratio():
    z, y = _noisy_data()
    for bad in (0.5, float("nan"), True, "10"):
        with pytest.raises(ParameterError, match="max_terms_ratio"):
            fit_pce(z, y, max_terms_ratio=bad)
