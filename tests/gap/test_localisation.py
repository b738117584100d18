"""Cells, gap-cell ranking and the Ljung-Box statistic against brute-force recomputation and known behaviour."""

import numpy as np
import pytest
from scipy.stats import chi2, kstest

from spflow.plugins.gap.error_model import BlockErrorModel
from spflow.plugins.gap.layout import Block, Layout
from spflow.plugins.gap.localisation import Cell, cells, gap_cells, ljung_box


def _layout():
    blocks = []
    for variable, n in (("dp", 12), ("oil_cut", 9)):
        pv = np.arange(1, n + 1) * 0.5
        slug = np.searchsorted([2.0, 4.0, 99.0], pv - 1e-9)
        blocks.append(Block(variable, "E", np.arange(n), pv, np.zeros(n), slug, BlockErrorModel(np.ones(n), 0.0)))
    return Layout(tuple(blocks))


def test_cells_match_brute_force():
    layout = _layout()
    rng = np.random.default_rng(0)
    w = rng.normal(size=layout.size)
    e = rng.normal(size=layout.size) * 3
    table = cells(layout, w, e, {"E": ["A", "B", "C"]})
    assert len(table) == 6
    for c in table:
        s = layout.slices()[[b.variable for b in layout.blocks].index(c.variable)]
        block = layout.blocks[[b.variable for b in layout.blocks].index(c.variable)]
        m = block.slug == c.slug
        ws, es = w[s][m], e[s][m]
        assert c.n == m.sum() and c.slug_name == "ABC"[c.slug]
        assert c.chi2 == pytest.approx(sum(x * x for x in ws))
        assert c.normalised_chi2 == pytest.approx(np.mean(ws**2))
        assert c.bias_z == pytest.approx(ws.sum() / np.sqrt(ws.size))
        assert c.rms == pytest.approx(np.sqrt(np.mean(es**2)))
        assert c.pvalue == pytest.approx(chi2.sf(np.sum(ws**2), ws.size))
        assert (c.pv_start, c.pv_end) == (block.pv[m].min(), block.pv[m].max())


def test_gap_cells_are_bonferroni_significant_and_ranked_by_excess():
    def cell(n, x):
        return Cell("dp", "E", 0, "A", 0.0, 1.0, n, x, 0.0, 1.0)

    table = [cell(10, 10.0), cell(10, 60.0), cell(40, 120.0), cell(10, 24.0)]
    # Bonferroni level 0.01 / 4: chi2_10 sf(24) = 0.0077 is not significant, the others are (or are not) by far
    found = gap_cells(table, 0.01)
    assert [c.chi2 for c in found] == [120.0, 60.0]
    assert gap_cells(table, 0.2)[-1].chi2 == 24.0


def test_ljung_box_matches_its_definition():
    rng = np.random.default_rng(5)
    w = rng.normal(size=60)
    q, p, h = ljung_box(w, lags=6)
    n = w.size
    rho = [np.correlate(w[k:], w[:-k])[0] / np.dot(w, w) for k in range(1, 7)]
    expected = n * (n + 2) * sum(r * r / (n - k) for k, r in enumerate(rho, 1))
    assert (h, q) == (6, pytest.approx(expected))
    assert p == pytest.approx(chi2.sf(expected, 6))


def test_ljung_box_is_calibrated_on_white_noise_and_rejects_ar1():
    rng = np.random.default_rng(7)
    white = [ljung_box(rng.normal(size=200))[1] for _ in range(300)]
    assert kstest(white, "uniform").pvalue > 0.001
    e = np.zeros(200)
    for t in range(1, 200):
        e[t] = 0.6 * e[t - 1] + rng.normal()
    assert ljung_box(e)[1] < 1e-6
    assert ljung_box(np.ones(3))[2] == 0  # too short for any lag: no test
