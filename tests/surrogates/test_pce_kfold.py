"""K-fold cross-validation of the whole adaptive PCE fit (pce_cross_validation.py) against brute-force refits done here
with numpy least squares: the reference re-implements each fold's fit (degree search scored by the corrected LOO,
OLS) from scratch on Legendre polynomials from numpy.polynomial."""

import numpy as np
import pytest
from numpy.polynomial import legendre

from spflow.core.errors import ParameterError
from spflow.plugins.surrogates.outputs import OutputIndex
from spflow.plugins.surrogates.folds import FOLD_SEED
from spflow.plugins.surrogates.pce_cross_validation import kfold_error
from spflow.plugins.surrogates.pce_model import PCE
from spflow.plugins.surrogates.pce_stage import PCEStage
from spflow.surrogates import PCE as PCERegressor


def _folds(n, k):
    """The documented fold rule: a permutation from default_rng(FOLD_SEED), cut into k near-equal consecutive parts."""
    order = np.random.default_rng(FOLD_SEED).permutation(n)
    sizes = [n // k + (1 if j < n % k else 0) for j in range(k)]
    return np.split(order, np.cumsum(sizes)[:-1])


def _orthonormal_legendre(z, degree):
    """(N, degree + 1) orthonormal Legendre columns sqrt(2n + 1) P_n(z) of one input on [-1, 1]."""
    return legendre.legvander(z, degree) * np.sqrt(2 * np.arange(degree + 1) + 1)


def _corrected_loo(psi, y):
    """Blatman & Sudret's corrected LOO of an OLS fit, by hand: N/(N-P) (1 + tr((Psi'Psi)^-1)) * mean LOO^2 / var."""
    n, p = psi.shape
    coef = np.linalg.lstsq(psi, y, rcond=None)[0]
    h = np.diag(psi @ np.linalg.inv(psi.T @ psi) @ psi.T)
    loo = np.mean(((y - psi @ coef) / (1 - h)) ** 2) / y.var()
    return n / (n - p) * (1 + np.trace(np.linalg.inv(psi.T @ psi))) * loo, coef


def _brute_force_cv(z, y, k, degree_max):
    """Each fold: OLS at every degree 1..degree_max (1 input), keep the smallest corrected LOO, predict the fold.
    Returns the relative error and the degrees the folds chose."""
    residuals, chosen = np.empty_like(y), []
    for held in _folds(y.size, k):
        train = np.setdiff1d(np.arange(y.size), held)
        fits = [_corrected_loo(_orthonormal_legendre(z[train], p), y[train]) + (p,) for p in range(1, degree_max + 1)]
        _, coef, p = min(fits, key=lambda f: f[0])
        residuals[held] = _orthonormal_legendre(z[held], p) @ coef - y[held]
        chosen.append(p)
    return np.mean(residuals**2) / y.var(), chosen


def test_kfold_error_matches_brute_force_refits_with_the_degree_search():
    rng = np.random.default_rng(3)
    z = rng.uniform(-1.0, 1.0, 37)
    y = np.exp(1.5 * z) + 0.3 * np.abs(z) + 0.02 * rng.standard_normal(37)  # the kink keeps every degree in play
    degrees = set()
    for k in (2, 5, 37):
        got = kfold_error(z[:, None], y[:, None], k, degree_max=6, q=1.0, solver="ols", early_stop=False)
        expected, chosen = _brute_force_cv(z, y, k, 6)
        assert got.shape == (1,) and got[0] == pytest.approx(expected, rel=1e-9), k
        degrees.update(chosen)
    assert len(degrees) > 1  # the folds' fits chose different degrees: the search inside the folds is covered


@pytest.mark.filterwarnings("ignore::spflow.core.errors.DegreeCapWarning")  # degree_max = 1 on purpose
def test_pce_reports_the_cross_validation_error_of_each_output_and_stores_it():
    rng = np.random.default_rng(8)
    x = rng.uniform(0.0, 2.0, (30, 2))
    y = np.column_stack([x[:, 0] ** 3 - x[:, 1] + 0.05 * rng.standard_normal(30), np.full(30, 4.0)])
    outputs = OutputIndex.of_array(2)
    model = PCE.fit(["a", "b"], np.zeros(2), np.full(2, 2.0), outputs, x, y, degree_max=1, q=1.0, cv_folds=6)
    # degree 1 only: each fold's fit is OLS on (1, a, b) -- a plane, whatever the scaling of the columns
    residuals = np.empty(30)
    for held in _folds(30, 6):
        train = np.setdiff1d(np.arange(30), held)
        design = np.column_stack([np.ones(train.size), x[train]])
        coef = np.linalg.lstsq(design, y[train, 0], rcond=None)[0]
        residuals[held] = np.column_stack([np.ones(held.size), x[held]]) @ coef - y[held, 0]
    expected = np.mean(residuals**2) / y[:, 0].var()
    assert model.cv_error == pytest.approx([expected, 0.0], rel=1e-9)  # a constant output has no error
    assert model.info["error_estimate"] == "kfold_cv" and model.info["cv_folds"] == 6
    assert model.error_variance == pytest.approx([expected * y[:, 0].var(), 0.0], rel=1e-9)
    assert model.predict(x[:3])[1][:, 0] == pytest.approx(np.full(3, expected * y[:, 0].var()), rel=1e-9)
    back = PCE.from_dataset(model.to_dataset())
    assert back.cv_error == pytest.approx(model.cv_error) and back.info["error_estimate"] == "kfold_cv"
    # without cv_folds the corrected LOO is reported, and no cv_error is stored
    plain = PCE.fit(["a", "b"], np.zeros(2), np.full(2, 2.0), outputs, x, y, degree_max=1, q=1.0)
    ds = plain.to_dataset()
    assert "cv_error" not in ds and ds.attrs["error_estimate"] == "corrected_loo" and ds.attrs["cv_folds"] == 0
    assert np.array_equal(plain.error_variance, plain.modified_loo * plain.output_variance)
    assert plain.coefficients == pytest.approx(model.coefficients)  # the final model is the fit on all points


@pytest.mark.filterwarnings("ignore::spflow.core.errors.DegreeCapWarning")
def test_regressor_loo_error_is_the_reported_estimate_and_defaults_agree():
    rng = np.random.default_rng(1)
    x = rng.uniform(-1.0, 1.0, (25, 1))
    y = np.sin(2.0 * x[:, 0])
    est = PCERegressor([[-1.0, 1.0]], degree_max=1, cv_folds=5).fit(x, y)
    residuals = np.empty(25)
    for held in _folds(25, 5):
        train = np.setdiff1d(np.arange(25), held)
        slope, intercept = np.polyfit(x[train, 0], y[train], 1)
        residuals[held] = slope * x[held, 0] + intercept - y[held]
    assert est.loo_error_ == pytest.approx(np.mean(residuals**2) / y.var(), rel=1e-9)
    assert PCERegressor().cv_folds == PCEStage.params["cv_folds"].default == 0


@pytest.mark.parametrize("folds, match", [
    (1, r"cv_folds must be 0 \(report the corrected LOO\) or an integer >= 2"),
    (2.5, r"cv_folds must be 0"),
    (-3, r"cv_folds must be 0"),
    (11, r"cv_folds = 11 exceeds the N = 10 training runs"),
    (2, r"cv_folds = 2 leaves 5 of the N = 10 training runs to a fold's fit; it needs at least 6 \(solver 'ols', "
        r"4 inputs\)"),
])
def test_bad_cv_folds_are_refused_before_fitting(folds, match):
    x = np.random.default_rng(0).uniform(0.0, 1.0, (10, 4))
    with pytest.raises(ParameterError, match=match):
        PCE.fit(list("abcd"), np.zeros(4), np.ones(4), OutputIndex.of_array(1), x, x[:, :1], cv_folds=folds)
    with pytest.raises(ParameterError, match=r"stage 'pce' parameter 'cv_folds' must be 0"):
        PCEStage(cv_folds=1)
