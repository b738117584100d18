"""Input distributions beyond uniform (issue #24): the orthonormal families against Gauss quadrature and closed forms,
the isoprobabilistic maps against the distributions' cdfs, and PCE moments and Sobol indices under normal, beta,
lognormal and truncated-normal inputs against variance decompositions worked out by hand (and chaospy)."""

import chaospy
import numpy as np
import pytest
import xarray as xr
from numpy.polynomial import hermite_e
from scipy import integrate, special, stats
from sklearn.base import clone

from spflow.core.errors import ParameterError
from spflow.core.stage import StageContext
from spflow.plugins.forward.stage import RESPONSE_UNITS
from spflow.plugins.surrogates.adaptive_design import AdaptivePCE
from spflow.plugins.surrogates.basis import design_matrix, multi_indices
from spflow.plugins.surrogates.contract import UNIFORM_ASSUMED, input_box, load_surrogate
from spflow.plugins.surrogates.input_marginals import marginal_from_record, marginal_variables
from spflow.plugins.surrogates.pce_stage import PCEStage
from spflow.plugins.surrogates.orthonormal_polynomials import HERMITE, LEGENDRE, jacobi, truncated_hermite
from spflow.plugins.surrogates.regression import ols
from spflow.surrogates import GP, PCE, PCK, Beta, LogNormal, Normal, TruncatedNormal, Uniform

JACOBI_EXPONENTS = [(0.0, 0.0), (1.5, -0.3), (-0.5, -0.5), (2.0, 4.0), (-0.7, 3.0)]


def _draw(inputs, n, seed):
    rng = np.random.default_rng(seed)
    return np.column_stack([m.sample(n, rng) for m in inputs])


# -- the families -----------------------------------------------------------------------------------------------------
def _gram(table, weights):
    return table @ (weights[:, None] * table.T)


def test_hermite_orthonormal_under_gauss_hermite_quadrature():
    nodes, weights = special.roots_hermitenorm(20)  # exact to degree 39 under exp(-x²/2)
    np.testing.assert_allclose(_gram(HERMITE.evaluate(nodes, 8), weights / weights.sum()), np.eye(9), atol=1e-12)


def test_legendre_orthonormal_under_gauss_legendre_quadrature():
    nodes, weights = special.roots_legendre(20)
    np.testing.assert_allclose(_gram(LEGENDRE.evaluate(nodes, 8), weights / weights.sum()), np.eye(9), atol=1e-12)


@pytest.mark.parametrize("a, b", JACOBI_EXPONENTS)
def test_jacobi_orthonormal_under_gauss_jacobi_quadrature(a, b):
    nodes, weights = special.roots_jacobi(20, a, b)  # weight (1 - x)^a (1 + x)^b
    np.testing.assert_allclose(_gram(jacobi(a, b).evaluate(nodes, 8), weights / weights.sum()), np.eye(9),
                               atol=1e-11)


@pytest.mark.parametrize("a, b", [(-2.0, 3.0), (0.5, 4.0), (-np.inf, -1.0), (-30.0, 30.0)])
def test_truncated_hermite_orthonormal_under_adaptive_quadrature(a, b):
    """Gram matrix by adaptive quadrature (scipy.integrate.quad_vec) of φ_m φ_n against the truncated normal density,
    independent of the Gauss-Legendre sums the recurrence is built from."""
    family, law = truncated_hermite(a, b), stats.truncnorm(a, b)

    def integrand(t):
        phi = family.evaluate(t, 8)[:, 0]
        return np.outer(phi, phi) * law.pdf(t)

    gram = integrate.quad_vec(integrand, max(a, -12.0), min(b, 12.0), epsabs=1e-13, epsrel=1e-12)[0]
    np.testing.assert_allclose(gram, np.eye(9), atol=1e-9)


def test_families_equal_the_normalised_classical_polynomials():
    """φ_n = He_n / sqrt(n!) and P_n^(a,b) / sqrt(h_n / mass), h_n the closed-form Jacobi norm (Abramowitz & Stegun
    22.2.1; n >= 1, its n = 0 form is 0/0 at a + b = -1), evaluated by numpy/scipy: same sign convention (positive
    leading coefficient), not only orthonormal."""
    z = np.linspace(-0.99, 0.99, 13)
    for n in range(9):
        he = hermite_e.hermeval(3 * z, np.eye(n + 1)[n]) / np.sqrt(special.factorial(n))
        np.testing.assert_allclose(HERMITE.evaluate(3 * z, 8)[n], he, rtol=1e-11, atol=1e-11)
    for a, b in JACOBI_EXPONENTS[1:]:
        mass = 2 ** (a + b + 1) * special.beta(a + 1, b + 1)
        np.testing.assert_array_equal(jacobi(a, b).evaluate(z, 8)[0], 1.0)
        for n in range(1, 9):
            log_h = ((a + b + 1) * np.log(2) - np.log(2 * n + a + b + 1) + special.gammaln(n + a + 1)
                     + special.gammaln(n + b + 1) - special.gammaln(n + a + b + 1) - special.gammaln(n + 1))
            reference = special.eval_jacobi(n, a, b, z) / np.sqrt(np.exp(log_h) / mass)
            np.testing.assert_allclose(jacobi(a, b).evaluate(z, 8)[n], reference, rtol=1e-10, atol=1e-10)


def test_jacobi_zero_zero_is_legendre():
    n = np.arange(1, 7)
    for family in (jacobi(0, 0), LEGENDRE):
        alpha, sqrt_beta = family.recurrence(6)
        np.testing.assert_allclose(alpha, 0.0, atol=1e-15)
        np.testing.assert_allclose(sqrt_beta[1:], n / np.sqrt(4 * n**2 - 1), rtol=1e-14)
    z = np.linspace(-1, 1, 11)
    np.testing.assert_allclose(jacobi(0, 0).evaluate(z, 8), LEGENDRE.evaluate(z, 8), rtol=1e-12, atol=1e-13)


def test_design_matrix_mixes_families_per_coordinate():
    indices = multi_indices(3, 4, 0.8)
    families = [HERMITE, jacobi(1.0, 2.0), LEGENDRE]
    z = np.random.default_rng(0).uniform(-1, 1, (20, 3)) * [3.0, 1.0, 1.0]
    tables = [f.evaluate(z[:, k], 4) for k, f in enumerate(families)]
    reference = np.prod([tables[k][indices[:, k]] for k in range(3)], axis=0).T
    np.testing.assert_allclose(design_matrix(z, indices, families), reference, rtol=1e-13, atol=1e-14)
    # all-Legendre by default: the same numbers as before the families existed
    np.testing.assert_array_equal(design_matrix(z[:, 1:] * 0.9, multi_indices(2, 5)),
                                  design_matrix(z[:, 1:] * 0.9, multi_indices(2, 5), [LEGENDRE, LEGENDRE]))


# -- the isoprobabilistic maps ----------------------------------------------------------------------------------------
MARGINALS = [Uniform(100, 200), Normal(1.0, 0.2), LogNormal(-1.0, 0.4), TruncatedNormal(0.3, 0.5, 0.0, 1.0),
             Beta(2.0, 5.0, -1.0, 3.0)]
#: cdf of the reference variable of each family: U[-1, 1], N(0, 1), N(0, 1), N(0, 1) truncated to [-0.6, 1.4],
#: 2 Beta(alpha, beta) - 1
REFERENCE_CDF = [lambda z: (z + 1) / 2, stats.norm.cdf, stats.norm.cdf, stats.truncnorm(-0.6, 1.4).cdf,
                 lambda z: stats.beta.cdf((z + 1) / 2, 2.0, 5.0)]


@pytest.mark.parametrize("k", range(len(MARGINALS)))
def test_map_sends_the_marginal_onto_its_reference_law(k):
    marginal, reference_cdf = MARGINALS[k], REFERENCE_CDF[k]
    x = marginal.ppf(np.linspace(0.01, 0.99, 25))
    z = marginal.to_reference(x)
    np.testing.assert_allclose(reference_cdf(z), marginal.cdf(x), atol=1e-12)
    np.testing.assert_allclose(marginal.from_reference(z), x, rtol=1e-10)


def test_marginals_match_scipy_parametrisations():
    x = np.linspace(0.05, 3.0, 7)
    np.testing.assert_allclose(LogNormal(-1.0, 0.4).cdf(x), stats.norm.cdf((np.log(x) + 1.0) / 0.4), rtol=1e-12)
    moments = LogNormal.from_moments(2.0, 0.5).frozen()
    np.testing.assert_allclose([moments.mean(), moments.std()], [2.0, 0.5], rtol=1e-12)
    t = (x - 1) / 2  # Beta(2, 5) on [1, 3]
    np.testing.assert_allclose(Beta(2, 5, 1, 3).cdf(x), np.where(x < 1, 0, special.betainc(2, 5, np.clip(t, 0, 1))),
                               atol=1e-12)


def test_record_round_trip():
    for marginal in MARGINALS:
        family, parameters = marginal.record()
        assert marginal_from_record(family, parameters) == marginal


# -- exact moments and Sobol indices ----------------------------------------------------------------------------------
def test_normal_inputs_bilinear_function_exact():
    """f = a1 x1 + a2 x2 + a3 x1 x3, x_i ~ N(m_i, s_i²) independent. With x_i = m_i + s_i z_i,
    f = const + (a1 s1 + a3 m3 s1) z1 + a2 s2 z2 + a3 m1 s3 z3 + a3 s1 s3 z1 z3, so V = c1² + c2² + c3² + c13²,
    S1 = (c1², c2², c3²)/V, ST = (c1² + c13², c2², c3² + c13²)/V."""
    (m1, s1), (m2, s2), (m3, s3), (a1, a2, a3) = (1.0, 0.2), (-2.0, 0.5), (0.5, 1.0), (2.0, 3.0, 1.5)
    inputs = [Normal(m1, s1), Normal(m2, s2), Normal(m3, s3)]
    x = _draw(inputs, 80, seed=1)
    model = PCE(inputs=inputs).fit(x, a1 * x[:, 0] + a2 * x[:, 1] + a3 * x[:, 0] * x[:, 2])
    c1, c2, c3, c13 = a1 * s1 + a3 * m3 * s1, a2 * s2, a3 * m1 * s3, a3 * s1 * s3
    v = c1**2 + c2**2 + c3**2 + c13**2
    mean, var = model.model_.moments()
    np.testing.assert_allclose(mean, a1 * m1 + a2 * m2 + a3 * m1 * m3, rtol=1e-12)
    np.testing.assert_allclose(var, v, rtol=1e-10)
    sobol = model.sobol_indices()
    np.testing.assert_allclose(sobol.first, np.array([c1**2, c2**2, c3**2]) / v, rtol=1e-9, atol=1e-14)
    np.testing.assert_allclose(sobol.total, np.array([c1**2 + c13**2, c2**2, c3**2 + c13**2]) / v, rtol=1e-9)
    group = model.model_.group_sobol(["x1", "x3"])
    np.testing.assert_allclose(group, c13**2 / v, rtol=1e-9)


def _beta_moments(alpha, beta, lower, upper):
    """Mean and E[x²] of Beta(alpha, beta) stretched onto [lower, upper], from the moments of Beta on [0, 1]."""
    width = upper - lower
    m1 = alpha / (alpha + beta)
    m2 = alpha * (alpha + 1) / ((alpha + beta) * (alpha + beta + 1))
    return lower + width * m1, lower**2 + 2 * lower * width * m1 + width**2 * m2


def test_beta_inputs_product_exact():
    """f = x1 x2 + x3² with independent beta inputs: E f = μ1 μ2 + E x3²; partial variances V1 = μ2² v1, V2 = μ1² v2,
    V12 = v1 v2, V3 = Var(x3²) = E x3⁴ − (E x3²)² (E x3⁴ from scipy's beta moments)."""
    params = [(2.0, 3.0, 0.0, 1.0), (0.5, 0.5, -1.0, 2.0), (4.0, 1.5, 1.0, 3.0)]
    inputs = [Beta(*p) for p in params]
    x = _draw(inputs, 120, seed=2)
    model = PCE(inputs=inputs).fit(x, x[:, 0] * x[:, 1] + x[:, 2] ** 2)
    (mu1, e1), (mu2, e2), (mu3, e3) = (_beta_moments(*p) for p in params)
    v1, v2 = e1 - mu1**2, e2 - mu2**2
    e34 = stats.beta(4.0, 1.5, loc=1.0, scale=2.0).moment(4)
    parts = {"1": mu2**2 * v1, "2": mu1**2 * v2, "12": v1 * v2, "3": e34 - e3**2}
    v = sum(parts.values())
    mean, var = model.model_.moments()
    np.testing.assert_allclose(mean, mu1 * mu2 + e3, rtol=1e-12)
    np.testing.assert_allclose(var, v, rtol=1e-10)
    sobol = model.sobol_indices()
    np.testing.assert_allclose(sobol.first, np.array([parts["1"], parts["2"], parts["3"]]) / v, rtol=1e-9)
    np.testing.assert_allclose(sobol.total, np.array([parts["1"] + parts["12"], parts["2"] + parts["12"],
                                                      parts["3"]]) / v, rtol=1e-9)


def test_lognormal_inputs_product():
    """f = x1 x2, ln x_i ~ N(mu_i, s_i²): E f = exp(mu1 + mu2 + (s1² + s2²)/2), V = E[x1²] E[x2²] − (E f)² with
    E[x²] = exp(2 mu + 2 s²); V1 = (E x2)² v1, V2 = (E x1)² v2, V12 = v1 v2. f = exp(mu + s1 z1 + s2 z2) is not a
    polynomial in z: its Hermite coefficients fall as s^n / sqrt(n!), so the expansion is exact to ~1e-9."""
    (mu1, s1), (mu2, s2) = (0.3, 0.25), (-1.0, 0.15)
    inputs = [LogNormal(mu1, s1), LogNormal(mu2, s2)]
    x = _draw(inputs, 200, seed=3)
    model = PCE(inputs=inputs).fit(x, x[:, 0] * x[:, 1])
    e1, e2 = np.exp(mu1 + s1**2 / 2), np.exp(mu2 + s2**2 / 2)
    v1, v2 = np.exp(2 * mu1 + 2 * s1**2) - e1**2, np.exp(2 * mu2 + 2 * s2**2) - e2**2
    parts = np.array([e2**2 * v1, e1**2 * v2, v1 * v2])
    mean, var = model.model_.moments()
    np.testing.assert_allclose(mean, e1 * e2, rtol=1e-9)
    np.testing.assert_allclose(var, parts.sum(), rtol=1e-7)
    sobol = model.sobol_indices()
    np.testing.assert_allclose(sobol.first, parts[:2] / parts.sum(), rtol=1e-6)
    np.testing.assert_allclose(sobol.total, (parts[:2] + parts[2]) / parts.sum(), rtol=1e-6)


def test_truncated_normal_input_through_its_cdf():
    """f = x1 (1 + x2) with x1 ~ N(1, 0.5²) truncated to [0, 2.5], x2 ~ U[0, 1]: V1 = (1 + E x2)² v1,
    V2 = (E x1)² v2, V12 = v1 v2 (moments of x1 from scipy.stats.truncnorm). The reference variable of x1 is affine in
    x1 (its family is orthonormal under the truncated normal), so the expansion is exact."""
    inputs = [TruncatedNormal(1.0, 0.5, 0.0, 2.5), Uniform(0.0, 1.0)]
    x = _draw(inputs, 300, seed=4)
    model = PCE(inputs=inputs).fit(x, x[:, 0] * (1 + x[:, 1]))
    parent = stats.truncnorm(-2.0, 3.0, loc=1.0, scale=0.5)
    e1, v1, e2, v2 = parent.mean(), parent.var(), 0.5, 1 / 12
    parts = np.array([(1 + e2) ** 2 * v1, e1**2 * v2, v1 * v2])
    mean, var = model.model_.moments()
    np.testing.assert_allclose(mean, e1 * (1 + e2), rtol=1e-11)
    np.testing.assert_allclose(var, parts.sum(), rtol=1e-9)
    sobol = model.sobol_indices()
    np.testing.assert_allclose(sobol.first, parts[:2] / parts.sum(), rtol=1e-9)
    np.testing.assert_allclose(sobol.total, (parts[:2] + parts[2]) / parts.sum(), rtol=1e-9)


def test_same_least_squares_as_chaospy_stieltjes_expansion():
    """A non-polynomial f under Beta x Normal inputs: OLS on spflow's total-degree-4 basis and chaospy's Stieltjes
    expansion of the same joint law span the same polynomials (the maps are affine), so the fitted means and
    variances agree."""
    inputs = [Beta(2.0, 3.0, 0.0, 1.0), Normal(1.0, 0.2)]
    joint = chaospy.J(chaospy.Beta(2.0, 3.0, 0.0, 1.0), chaospy.Normal(1.0, 0.2))
    x = _draw(inputs, 60, seed=5)
    y = np.exp(x[:, 0]) * np.sin(x[:, 1])
    peer = chaospy.fit_regression(chaospy.expansion.stieltjes(4, joint, normed=True), x.T, y)
    z = np.column_stack([m.to_reference(x[:, k]) for k, m in enumerate(inputs)])
    fit = ols(design_matrix(z, multi_indices(2, 4), [m.polynomials for m in inputs]), y)
    np.testing.assert_allclose(fit.coefficients[0], chaospy.E(peer, joint), rtol=1e-9)
    np.testing.assert_allclose(np.sum(fit.coefficients[1:] ** 2), chaospy.Var(peer, joint), rtol=1e-7)


def test_truncated_hermite_equals_chaospy_stieltjes_polynomials():
    """chaospy's normed Stieltjes expansion of N(1, 0.5²) truncated to [0, 2.5], at the same points: the same
    polynomials of x (up to round-off), as the reference map is (x − 1)/0.5."""
    marginal = TruncatedNormal(1.0, 0.5, 0.0, 2.5)
    expansion = chaospy.expansion.stieltjes(6, chaospy.TruncNormal(0.0, 2.5, mu=1.0, sigma=0.5), normed=True)
    x = np.linspace(0.0, 2.5, 11)
    ours = marginal.polynomials.evaluate(marginal.to_reference(x), 6)
    np.testing.assert_allclose(ours, np.asarray(expansion(x)), rtol=1e-6, atol=1e-6)


# -- uniform unchanged, Kriging, storage ------------------------------------------------------------------------------
def test_uniform_inputs_equal_bounds_bit_for_bit():
    box = [(-np.pi, np.pi)] * 3
    x = _draw([Uniform(*b) for b in box], 150, seed=6)
    y = np.sin(x[:, 0]) + 7 * np.sin(x[:, 1]) ** 2 + 0.1 * x[:, 2] ** 4 * np.sin(x[:, 0])  # Ishigami
    by_bounds = PCE(box).fit(x, y).model_
    by_inputs = PCE(inputs=[Uniform(*b) for b in box]).fit(x, y).model_
    np.testing.assert_array_equal(by_inputs.indices, by_bounds.indices)
    np.testing.assert_array_equal(by_inputs.coefficients, by_bounds.coefficients)


def test_estimator_with_inputs_clones_and_keeps_them():
    inputs = [Normal(0.0, 1.0), Beta(2.0, 2.0)]
    model = PCE(inputs=inputs, degree_max=3)
    copy = clone(model)
    assert copy.get_params()["inputs"] == inputs and copy.get_params()["bounds"] is None
    x = _draw(inputs, 30, seed=13)
    np.testing.assert_array_equal(copy.fit(x, x[:, 0]).predict(x), model.fit(x, x[:, 0]).predict(x))


def test_kriging_in_the_reference_space():
    inputs = [Normal(10.0, 2.0), Beta(2.0, 2.0, 0.0, 1.0)]
    x = _draw(inputs, 30, seed=7)
    y = x[:, 0] + x[:, 1] ** 2
    gp = GP(inputs=inputs, restarts=1).fit(x, y)
    np.testing.assert_allclose(gp.model_.to_unit(x), np.column_stack([(x[:, 0] - 10.0) / 2.0, 2 * x[:, 1] - 1]))
    np.testing.assert_allclose(gp.predict(x), y, rtol=1e-3)  # (near-)interpolates its training points: same map
    # a polynomial trend of the normal/beta families carries f: PC-Kriging's trend Sobol indices are f's,
    # V1 = 4 (std 2 of x1), V2 = Var(x2²) for Beta(2, 2): E x² = 3/10, E x⁴ = 1/7 (Beta moments)
    pck = PCK(inputs=inputs, degree_max=2, restarts=1).fit(x, y)
    v2 = 1 / 7 - 0.09
    np.testing.assert_allclose(pck.sobol_indices(part="trend").first, np.array([4.0, v2]) / (4.0 + v2), rtol=1e-5)


@pytest.mark.parametrize("estimator", [PCE, GP])
def test_marginals_round_trip_through_netcdf(tmp_path, estimator):
    inputs = [LogNormal(0.0, 0.3), TruncatedNormal(0.5, 0.2, 0.0, 1.0), Normal(-1.0, 3.0)]
    x = _draw(inputs, 40, seed=8)
    model = estimator(inputs=inputs, **({"restarts": 1} if estimator is GP else {})).fit(x, x.sum(axis=1)).model_
    ds = model.to_dataset()
    assert list(ds["distribution"].values) == ["lognormal", "truncated_normal", "normal"]
    ds.to_netcdf(tmp_path / "s.nc")
    with xr.open_dataset(tmp_path / "s.nc") as stored:
        loaded = load_surrogate(stored.load())
    assert loaded.inputs == inputs and loaded.input_note == ""
    np.testing.assert_array_equal(loaded.lower, [0.0, 0.0, -np.inf])
    np.testing.assert_array_equal(loaded.upper, [np.inf, 1.0, np.inf])
    np.testing.assert_allclose(loaded.predict(x[:5])[0], model.predict(x[:5])[0], rtol=1e-10)


def test_a_dataset_without_marginals_loads_as_uniform_and_says_so():
    x = _draw([Uniform(0, 1), Uniform(2, 3)], 30, seed=9)
    model = PCE([(0, 1), (2, 3)]).fit(x, x[:, 0] * x[:, 1]).model_
    old = model.to_dataset().drop_vars(["distribution", "distribution_parameters"])
    loaded = load_surrogate(old)
    assert loaded.inputs == [Uniform(0, 1), Uniform(2, 3)]
    assert loaded.input_note == UNIFORM_ASSUMED
    np.testing.assert_array_equal(loaded.predict(x)[0], model.predict(x)[0])


# -- bad input --------------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("build, match", [
    (lambda: Normal(0.0, 0.0), r"Normal: std = 0.0 is out of range; allowed \(0, inf\)"),
    (lambda: Normal(np.nan, 1.0), r"Normal: mean = nan must be finite"),
    (lambda: LogNormal(0.0, -1.0), r"LogNormal: sigma = -1.0 is out of range; allowed \(0, inf\)"),
    (lambda: Uniform(1.0, 0.0), r"Uniform: lower must be < upper, got lower = 1, upper = 0"),
    (lambda: Beta(0.0, 1.0), r"Beta: alpha = 0.0 is out of range; allowed \(0, inf\)"),
    (lambda: Beta(1.0, 2.0, 3.0, 3.0), r"Beta: lower must be < upper"),
    (lambda: TruncatedNormal(0.0, 1.0, 40.0, 41.0), r"TruncatedNormal: \[lower, upper\] = \[40, 41\] holds"),
    (lambda: TruncatedNormal(0.0, "a", 0.0, 1.0), r"TruncatedNormal: std must be a number in \(0, inf\), got 'a'"),
    (lambda: marginal_from_record("gamma", "{}"), r"input distribution 'gamma' is not known"),
    (lambda: marginal_from_record("normal", '{"mean": 1}'), r"normal input needs the parameters \['mean', 'std'\]"),
])
def test_bad_marginals(build, match):
    with pytest.raises(ParameterError, match=match):
        build()


def test_bad_estimator_inputs():
    beta = [Beta(2.0, 2.0, 0.0, 1.0), Normal(0.0, 1.0)]
    x = np.array([[0.5, 0.0], [0.2, 1.0], [0.7, -1.0], [0.4, 2.0]])
    with pytest.raises(ParameterError, match=r"X\[1, 0\] = 1.5 lies outside the support \[0, 1\] of inputs\[0\]"):
        PCE(inputs=beta).fit(np.array([[0.5, 0.0], [1.5, 0.0]]), [1.0, 2.0])
    with pytest.raises(ParameterError, match=r"support \(0, inf\) of inputs\[0\] = LogNormal"):
        PCE(inputs=[LogNormal(0, 1)]).fit([[1.0], [0.0]], [1.0, 2.0])
    with pytest.raises(ParameterError, match="exactly one of bounds .* got both"):
        PCE([(0, 1), (0, 1)], inputs=beta).fit(x, x[:, 0])
    with pytest.raises(ParameterError, match="exactly one of bounds .* got neither"):
        GP().fit(x, x[:, 0])
    with pytest.raises(ParameterError, match="inputs must be a non-empty list of marginal distributions"):
        PCK(inputs=[(0, 1)]).fit(x[:, :1], x[:, 0])
    model = PCE(inputs=beta).fit(_draw(beta, 20, seed=10), np.arange(20.0))
    with pytest.raises(ParameterError, match=r"X\[0, 0\] = -0.1 lies outside the support \[0, 1\]"):
        model.predict([[-0.1, 0.0]])
    with pytest.raises(ParameterError, match=r"surrogate input: point 0 has x1 = -0.1, outside the support \[0, 1\]"):
        model.model_.predict(np.array([[-0.1, 0.0]]))


# -- a parameter space that records marginals (the priors stage's truncated normals) -----------------------------------
SPACE_NAMES = ["AD31", "HBNC71"]
SPACE_INPUTS = [TruncatedNormal(1.0, 0.4, 0.2, 2.0), Beta(2.0, 3.0, 0.01, 0.02)]


def _space(inputs=SPACE_INPUTS):
    lower, upper = input_box(inputs)
    return xr.Dataset({"lower": ("param", lower, {"units_variable": "unit"}),
                       "upper": ("param", upper, {"units_variable": "unit"}),
                       "default": ("param", (lower + upper) / 2, {"units_variable": "unit"}),
                       "unit": ("param", ["1", "1"]), **marginal_variables(inputs)},
                      coords={"param": SPACE_NAMES})


def _stage_data(x):
    """A design on the space and dp responses pv x1 + (100 x2)² at pv = 0.5, 1 (one experiment)."""
    design = xr.Dataset({"values": (("sample", "param"), x)}, coords={"sample": np.arange(len(x)),
                                                                      "param": SPACE_NAMES})
    pv = np.array([0.5, 1.0])
    dp = pv[None, :] * x[:, :1] + (100 * x[:, 1:]) ** 2
    responses = xr.Dataset({"dp": (("sample", "experiment", "pv"), dp[:, None, :], {"units": RESPONSE_UNITS["dp"]}),
                            "total_pv": ("experiment", [1.0], {"units": "1"})},
                           coords={"sample": np.arange(len(x)), "experiment": ["BCF1"], "pv": pv})
    return design, responses, pv


def test_pce_stage_fits_under_the_space_marginals():
    """E[dp] = pv E x1 + 10⁴ E x2², Var = pv² v1 + 10⁸ Var(x2²) with the truncated normal's moments from scipy and
    the beta's from its raw moments: exact, as the responses are polynomial."""
    x = _draw(SPACE_INPUTS, 40, seed=11)
    design, responses, pv = _stage_data(x)
    ds = PCEStage(variables=["dp"], experiments=["BCF1"]).run(StageContext(node="t", verbose=False),
                                                               space=_space(), design=design, responses=responses)
    assert list(ds["distribution"].values) == ["truncated_normal", "beta"]
    model = load_surrogate(ds)
    assert model.inputs == SPACE_INPUTS
    t = stats.truncnorm((0.2 - 1.0) / 0.4, (2.0 - 1.0) / 0.4, loc=1.0, scale=0.4)
    b = stats.beta(2.0, 3.0, loc=0.01, scale=0.01)
    mean, var = model.moments()
    np.testing.assert_allclose(mean, pv * t.mean() + 1e4 * b.moment(2), rtol=1e-10)
    np.testing.assert_allclose(var, pv**2 * t.var() + 1e8 * (b.moment(4) - b.moment(2) ** 2), rtol=1e-8)


def test_space_marginals_must_live_on_the_range():
    space = _space().assign(lower=("param", [0.0, 0.01], {"units_variable": "unit"}))
    x = _draw(SPACE_INPUTS, 10, seed=12)
    design, responses, _ = _stage_data(x)
    with pytest.raises(ParameterError, match=r"parameter 'AD31' of the space has the distribution "
                                             r"TruncatedNormal\(.*\) with support \[0.2, 2\], not the space's range "
                                             r"\[0, 2\]"):
        PCEStage(variables=["dp"], experiments=["BCF1"]).run(StageContext(node="t", verbose=False), space=space,
                                                             design=design, responses=responses)
    bad = _space().assign(distribution=("param", ["truncated_normal", "gamma"]))
    with pytest.raises(ParameterError, match="the parameter space, parameter 'HBNC71': input distribution 'gamma'"):
        PCEStage(variables=["dp"], experiments=["BCF1"]).run(StageContext(node="t", verbose=False), space=bad,
                                                             design=design, responses=responses)


def test_adaptive_pce_draws_its_hypercube_through_the_marginals():
    """Each column of a batch, mapped through its marginal's cdf, has one value in each of the n strata of [0, 1]."""
    n = 16
    batch = AdaptivePCE(n_initial=n)._batch(_space(), n, 0)
    values = batch["values"].transpose("sample", "param").values
    for j, marginal in enumerate(SPACE_INPUTS):
        strata = np.floor(marginal.cdf(values[:, j]) * n).astype(int)
        assert sorted(strata) == list(range(n))
