"""The q-norm Legendre basis: truncation sizes (thesis §3.5), exact orthonormality under the uniform measure, and
equality with chaospy's normed expansion, including for index sets that are not downward closed."""

import itertools

import chaospy
import numpy as np
import pytest

from spflow.core.errors import ParameterError
from spflow.plugins.surrogates.basis import design_matrix, multi_indices


@pytest.mark.parametrize("degree, size", [(1, 10), (2, 19), (3, 64), (4, 229), (5, 724)])
def test_thesis_basis_sizes_d9_q09(degree, size):
    assert multi_indices(9, degree, 0.9).shape == (size, 9)


def test_full_total_degree_size():
    assert multi_indices(9, 5, 1.0).shape[0] == 2002  # binomial(14, 5)


@pytest.mark.parametrize("d, p, q", [(2, 5, 0.9), (3, 4, 0.5), (4, 5, 0.9), (3, 6, 0.75), (5, 3, 1.0)])
def test_index_set_equals_brute_force_q_norm(d, p, q):
    brute = {a for a in itertools.product(range(p + 1), repeat=d)
             if sum(ai**q for ai in a) ** (1 / q) <= p + 1e-9}
    got = multi_indices(d, p, q)
    assert {tuple(int(v) for v in row) for row in got} == brute
    assert len(got) == len(brute)
    assert (got[0] == 0).all()
    assert np.all(np.diff(got.sum(axis=1)) >= 0)  # graded: constant first, then by total degree


def test_orthonormal_under_gauss_legendre_quadrature():
    d, p = 3, 4
    idx = multi_indices(d, p, 1.0)
    nodes, weights = np.polynomial.legendre.leggauss(p + 1)  # exact to degree 2p + 1 per dimension
    grid = np.array(list(itertools.product(nodes, repeat=d)))
    w = np.prod(np.array(list(itertools.product(weights / 2.0, repeat=d))), axis=1)  # uniform density on [-1,1]^d
    psi = design_matrix(grid, idx)
    np.testing.assert_allclose(psi.T @ (w[:, None] * psi), np.eye(idx.shape[0]), atol=1e-12)


@pytest.mark.parametrize("d, p, q", [(4, 4, 0.75), (2, 7, 1.0), (9, 3, 0.9)])
def test_equals_chaospy_normed_expansion(d, p, q):
    dist = chaospy.Iid(chaospy.Uniform(-1.0, 1.0), d)
    expansion = chaospy.generate_expansion(p, dist, normed=True, cross_truncation=q)
    z = np.random.default_rng(3).uniform(-1, 1, (50, d))
    reference = np.asarray(expansion(*z.T)).T
    np.testing.assert_allclose(design_matrix(z, multi_indices(d, p, q)), reference, rtol=1e-9, atol=1e-11)


def test_subset_and_shuffled_indices_give_the_matching_columns():
    full = multi_indices(5, 5, 0.8)
    z = np.random.default_rng(0).uniform(-1, 1, (30, 5))
    psi = design_matrix(z, full)
    rows = np.random.default_rng(1).permutation(full.shape[0])[:25]  # parents mostly missing: not downward closed
    np.testing.assert_allclose(design_matrix(z, full[rows]), psi[:, rows], rtol=1e-12, atol=1e-14)


def test_bad_input():
    idx = multi_indices(3, 2)
    with pytest.raises(ParameterError, match="coordinates"):
        design_matrix(np.zeros((4, 2)), idx)
    with pytest.raises(ParameterError, match="non-negative"):
        design_matrix(np.zeros((4, 3)), -idx)
    with pytest.raises(ParameterError, match="repeated"):
        design_matrix(np.zeros((4, 3)), np.vstack([idx, idx[-1:]]))
    with pytest.raises(ParameterError, match="q-norm"):
        multi_indices(3, 2, 0.0)
    with pytest.raises(ParameterError, match="degree"):
        multi_indices(3, -1)
