"""Numerical building blocks of the time loop against independent references computed in the test.

* ``transport.solve_dispersion`` (the batched backward-Euler dispersion solve, Eq. 1.9) against a dense solve of the
  same linear system assembled here with numpy, species by species, and against itself one species at a time
  (batching must not couple the species: bit-identical rows).
* ``physics.relative_permeability.corey`` at the end points of the mobile window, where it skips ``pow``: the result
  bits must equal ``kr0 * sbar ** n`` evaluated by Python (C ``pow``).
"""

import numpy as np
import pytest

from spflow.plugins.forward.physics.relative_permeability import corey
from spflow.plugins.forward.transport import solve_dispersion


def _dense_backward_euler(storage, conc, coef, lam):
    """Solve ``storage_i c_i - lam [K+ (c_{i+1} - c_i) - K- (c_i - c_{i-1})] = storage_i conc_i`` densely, with the
    face coefficient the mean of the two cells and no flux through the end faces; return the face fluxes
    ``-K_j (c_j - c_{j-1})`` (0 at both ends)."""
    n = storage.size
    k_face = 0.5 * (coef[:-1] + coef[1:]) * lam  # faces 1..n-1
    a = np.diag(storage.astype(float))
    for j, k in enumerate(k_face):  # face between cells j and j+1
        a[j, j] += k
        a[j + 1, j + 1] += k
        a[j, j + 1] -= k
        a[j + 1, j] -= k
    c = np.linalg.solve(a, storage * conc)
    flux = np.zeros(n + 1)
    flux[1:-1] = -0.5 * (coef[:-1] + coef[1:]) * np.diff(c)
    return flux


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_batched_dispersion_matches_dense_solve(seed):
    rng = np.random.default_rng(seed)
    m, n, lam = 4, 37, 17.0
    storage = rng.uniform(0.05, 1.0, (m, n))
    conc = rng.uniform(0.0, 1.0, (m, n))
    coef = rng.uniform(0.0, 0.05, (m, n))
    flux = np.zeros((m, n + 1))
    solve_dispersion(storage, conc, coef, n, lam, np.zeros((m, n)), np.zeros((m, n)), flux)
    for k in range(m):
        ref = _dense_backward_euler(storage[k], conc[k], coef[k], lam)
        np.testing.assert_allclose(flux[k], ref, rtol=1e-10, atol=1e-13)
        # conservative update: the dispersed amounts sum to the original ones
        updated = storage[k] * conc[k] - lam * np.diff(flux[k])
        assert abs(updated.sum() - (storage[k] * conc[k]).sum()) <= 1e-12 * (storage[k] * conc[k]).sum()


def test_batched_dispersion_rows_equal_single_species_solves():
    rng = np.random.default_rng(7)
    m, n, lam = 4, 25, 3.0
    storage = rng.uniform(0.0, 1.0, (m, n))
    storage[2, 5] = 0.0  # an empty cell (no storage) in one species only
    conc = rng.uniform(0.0, 1.0, (m, n))
    coef = rng.uniform(0.0, 0.1, (m, n))
    batched = np.zeros((m, n + 1))
    solve_dispersion(storage, conc, coef, n, lam, np.zeros((m, n)), np.zeros((m, n)), batched)
    for k in range(m):
        single = np.zeros((1, n + 1))
        solve_dispersion(storage[k:k + 1], conc[k:k + 1], coef[k:k + 1], n, lam, np.zeros((1, n)),
                         np.zeros((1, n)), single)
        assert np.array_equal(single[0], batched[k])


@pytest.mark.parametrize("n", [1.0, 1.5, 2.0, 2.718281828459045, 6.0])
@pytest.mark.parametrize("kr0", [0.0, 0.1, 0.8, 1.0])
@pytest.mark.parametrize("sbar", [0.0, 1.0, 0.3, 1.0 - 2.0**-52, 2.0**-40])
def test_corey_end_points_bit_identical_to_pow(kr0, sbar, n):
    assert corey(kr0, sbar, n) == kr0 * sbar**n
    assert np.signbit(corey(kr0, sbar, n)) == np.signbit(kr0 * sbar**n)


def test_corey_zero_saturation_with_non_positive_exponent_uses_pow():
    # an extrapolated exponent (Eq. 2.13 beyond the high-Nc residual) can reach <= 0: no shortcut there
    assert corey(0.5, 0.0, 0.0) == 0.5 * 0.0**0.0 == 0.5
    with np.errstate(divide="ignore"):
        assert corey(0.5, 0.0, -1.0) == np.inf
