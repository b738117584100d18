"""Sobol' indices through spflow's screening code (design -> evaluation matrix -> indices Dataset -> selection) on
functions with analytic indices (Ishigami; Sobol' G-function; tests/oracles/sensitivity_benchmarks.py)."""

import numpy as np
import pytest
from oracles.sensitivity_benchmarks import (
    G_STANDARD_A, ISHIGAMI_BOUNDS, ishigami, ishigami_moments, sobol_g, sobol_g_moments)

from spflow.plugins.screening.selection import SelectionRule
from spflow.plugins.screening.sobol import sobol_indices, sobol_runs, sobol_sample

ISHIGAMI_NAMES = ["x1", "x2", "x3"]
G_NAMES = [f"x{i + 1}" for i in range(G_STANDARD_A.size)]


def _ishigami_indices(samples, seed, calc_second_order=False):
    lo, hi = np.full(3, ISHIGAMI_BOUNDS[0]), np.full(3, ISHIGAMI_BOUNDS[1])
    x = sobol_sample(ISHIGAMI_NAMES, lo, hi, samples, calc_second_order=calc_second_order, seed=seed)
    assert x.shape == (sobol_runs(samples, 3, calc_second_order), 3)
    assert (x >= lo).all() and (x <= hi).all()
    return sobol_indices(ishigami(x), ISHIGAMI_NAMES, calc_second_order=calc_second_order, seed=seed + 1)


def _g_indices(samples, seed):
    d = G_STANDARD_A.size
    x = sobol_sample(G_NAMES, np.zeros(d), np.ones(d), samples, seed=seed)
    return sobol_indices(sobol_g(x, G_STANDARD_A), G_NAMES, seed=seed + 1)


def test_ishigami_first_and_total_indices_within_0p03_at_n8192():
    ref = ishigami_moments(a=7.0, b=0.1)
    ds = _ishigami_indices(8192, seed=5)
    assert ds["S1"].dims == ("qoi", "param") and ds["S1"].attrs["units"] == "1"
    np.testing.assert_allclose(ds["S1"].values[0], ref["S"], atol=0.03)
    np.testing.assert_allclose(ds["ST"].values[0], ref["ST"], atol=0.03)
    assert float(ds["variance"][0]) == pytest.approx(ref["variance"], rel=0.02)
    # the bootstrap half-widths are of the size of the error, not vacuous
    assert (ds["S1_conf"].values > 0).all() and (ds["S1_conf"].values < 0.05).all()
    # selection on the estimated indices: x3 matters only through its interaction with x1 (S3 = 0, ST3 = 0.24)
    s1_rule = SelectionRule(threshold=0.1)
    assert s1_rule.apply(ds["S1"].values[0], np.array(["g"] * 3)).tolist() == [True, True, False]
    assert s1_rule.apply(ds["ST"].values[0], np.array(["g"] * 3)).tolist() == [True, True, True]


def test_ishigami_second_order_interaction_x1_x3():
    ref = ishigami_moments(a=7.0, b=0.1)
    ds = _ishigami_indices(4096, seed=9, calc_second_order=True)
    s2 = ds["S2"].isel(qoi=0)
    assert s2.dims == ("param", "param_j")
    assert float(s2.sel(param="x1", param_j="x3")) == pytest.approx(ref["S13"], abs=0.03)
    assert abs(float(s2.sel(param="x1", param_j="x2"))) < 0.03
    assert abs(float(s2.sel(param="x2", param_j="x3"))) < 0.03
    assert np.isnan(s2.sel(param="x3", param_j="x1"))  # only the upper triangle is estimated


def test_g_function_indices_within_0p02_and_selection_picks_the_important_inputs():
    ref = sobol_g_moments(G_STANDARD_A)
    ds = _g_indices(8192, seed=21)
    np.testing.assert_allclose(ds["S1"].values[0], ref["S"], atol=0.02)
    np.testing.assert_allclose(ds["ST"].values[0], ref["ST"], atol=0.02)
    st, one_group = ds["ST"].values[0], np.array(["g"] * G_STANDARD_A.size)
    # analytic ST = 0.787, 0.242, 0.034, 0.0105, then 1e-4 for the four a = 99 inputs
    assert np.array(G_NAMES)[SelectionRule(threshold=0.1).apply(st, one_group)].tolist() == ["x1", "x2"]
    assert np.array(G_NAMES)[SelectionRule(threshold=0.02).apply(st, one_group)].tolist() == ["x1", "x2", "x3"]
    assert np.array(G_NAMES)[SelectionRule(threshold=0.0, top_k=4).apply(st, one_group)].tolist() == G_NAMES[:4]
    assert np.array(G_NAMES)[SelectionRule(threshold=0.2, top_k=3).apply(st, one_group)].tolist() == ["x1", "x2"]


def test_constant_and_ignored_outputs_get_exactly_zero_indices():
    lo, hi = np.full(3, ISHIGAMI_BOUNDS[0]), np.full(3, ISHIGAMI_BOUNDS[1])
    x = sobol_sample(ISHIGAMI_NAMES, lo, hi, 256, seed=3)
    y = np.column_stack([np.full(len(x), 2.5),                       # constant QoI: no variance to share
                         np.sin(x[:, 0]) + 7.0 * np.sin(x[:, 1]) ** 2])  # Ishigami with b = 0: x3 is ignored
    ds = sobol_indices(y, ISHIGAMI_NAMES, seed=4)
    for k in ("S1", "S1_conf", "ST", "ST_conf"):
        assert (ds[k].values[0] == 0.0).all()
    assert ds["ST"].values[1, 2] == 0.0 and ds["S1"].values[1, 2] == 0.0
    ref = ishigami_moments(a=7.0, b=0.0)
    np.testing.assert_allclose(ds["ST"].values[1, :2], ref["ST"][:2], atol=0.1)
