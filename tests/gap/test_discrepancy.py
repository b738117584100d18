"""The generic-discrepancy competitor against a hand generalised least-squares fit (dense AR(1) whitening matrix
built here), and its transfer to a held-out coreflood as per-slug-type means."""

import math

import numpy as np

from spflow.plugins.gap.discrepancy import fit_discrepancy
from spflow.plugins.gap.error_model import BlockErrorModel
from spflow.plugins.gap.layout import Block, Layout


def whitening_matrix(scale, phi):
    """Dense W with W e = the AR(1) innovations of e / scale (first point unscaled by the stationary factor)."""
    n = scale.size
    w = np.zeros((n, n))
    w[0, 0] = 1.0 / scale[0]
    for t in range(1, n):
        w[t, t] = 1.0 / (scale[t] * math.sqrt(1.0 - phi**2))
        w[t, t - 1] = -phi / (scale[t - 1] * math.sqrt(1.0 - phi**2))
    return w


def legendre_by_hand(pv):
    x = 2.0 * (pv - pv.min()) / (pv.max() - pv.min()) - 1.0
    return np.column_stack([np.ones_like(x), x, 0.5 * (3.0 * x**2 - 1.0)])


def block(variable, experiment, pv, slug, scale, phi, observed=None):
    index = np.arange(pv.size)
    return Block(variable, experiment, index, pv, np.zeros(pv.size) if observed is None else observed,
                 np.asarray(slug), BlockErrorModel(np.asarray(scale, float), phi))


def test_discrepancy_is_the_generalised_least_squares_fit_per_slug_window():
    rng = np.random.default_rng(3)
    pv = np.linspace(0.05, 2.0, 40)
    slug = np.where(pv < 0.8, 0, 1)
    scale = 0.5 + rng.random(40)
    layout = Layout((block("dp", "A", pv, slug, scale, 0.6),))
    residual = rng.normal(size=40) + 3.0 * pv
    disc = fit_discrepancy(layout, residual, {"A": ["WF", "P"]}, degree=2)
    # hand GLS: piecewise quadratic basis (one per slug window), min ||W (r + B c)||
    basis = np.zeros((40, 6))
    for k in (0, 1):
        rows = slug == k
        basis[rows, 3 * k: 3 * k + 3] = legendre_by_hand(pv[rows])
    w = whitening_matrix(scale, 0.6)
    a = w @ basis
    c = np.linalg.solve(a.T @ a, -a.T @ (w @ residual))
    np.testing.assert_allclose(disc.delta, basis @ c, rtol=1e-9, atol=1e-9)
    left = w @ (residual + basis @ c)
    np.testing.assert_allclose(disc.chi2, left @ left, rtol=1e-9)
    assert disc.n_terms == 6


def test_a_piecewise_quadratic_gap_is_closed_and_transferred_as_per_slug_type_means():
    pv_a = np.linspace(0.1, 2.0, 20)
    pv_b = np.linspace(0.1, 1.5, 15)
    slug_a = np.where(pv_a < 1.0, 0, 1)            # A: WF then P
    slug_b = np.where(pv_b < 0.5, 0, 1)            # B: WF then CW
    gap_a = np.where(slug_a == 0, 0.2 + 0.1 * pv_a**2, -1.0 + 0.3 * pv_a)
    gap_b = np.where(slug_b == 0, 0.4, 2.0 - pv_b)
    layout = Layout((block("dp", "A", pv_a, slug_a, np.ones(20), 0.0),
                     block("dp", "B", pv_b, slug_b, np.full(15, 2.0), 0.3)))
    names = {"A": ["WF", "P"], "B": ["WF", "CW"], "H": ["WF", "P", "CW", "SP"]}
    residual = -np.concatenate([gap_a, gap_b])        # model - data: the data sit above the model by ``gap``
    disc = fit_discrepancy(layout, residual, names, degree=2)
    np.testing.assert_allclose(disc.delta, np.concatenate([gap_a, gap_b]), atol=1e-9)
    assert disc.chi2 < 1e-16
    # transfer: mean discrepancy over the calibration points of each (variable, slug name), 0 for unseen names
    wf = np.concatenate([gap_a[slug_a == 0], gap_b[slug_b == 0]]).mean()
    expected = {"WF": wf, "P": gap_a[slug_a == 1].mean(), "CW": gap_b[slug_b == 1].mean(), "SP": 0.0}
    pv_h = np.linspace(0.1, 4.0, 8)
    slug_h = np.array([0, 0, 1, 1, 2, 2, 3, 3])
    held = Layout((block("dp", "H", pv_h, slug_h, np.ones(8), 0.0),))
    shift = disc.shift(held, names)
    np.testing.assert_allclose(shift, [expected[names["H"][k]] for k in slug_h], atol=1e-12)
