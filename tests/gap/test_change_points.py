"""Change points inside slugs: the statistic against brute force, the Monte Carlo null against a closed form, known
change points found where they are, and white noise flagged at the nominal rate over many seeds."""

import numpy as np
import pytest
from scipy import integrate
from scipy.stats import binom, chi2, kstest, norm

from spflow.core.errors import ParameterError
from spflow.plugins.gap.change_points import change_points, max_shift_statistic, segment, shift_pvalue
from spflow.plugins.gap.error_model import BlockErrorModel
from spflow.plugins.gap.layout import Block, Layout


def brute_force(x, m):
    best = (-1.0, None)
    for k in range(m, x.size - m + 1):
        a, b = x[:k], x[k:]
        rss = np.sum((a - a.mean()) ** 2) + np.sum((b - b.mean()) ** 2)
        s = max(1.0, np.sqrt(rss / (x.size - 2)))
        t = abs(b.mean() - a.mean()) / (s * np.sqrt(1 / k + 1 / (x.size - k)))
        best = max(best, (t, k))
    return best


@pytest.mark.parametrize("scale", [0.3, 1.0, 3.0])
def test_statistic_matches_brute_force(scale):
    rng = np.random.default_rng(1)
    for n, m in ((6, 3), (17, 2), (40, 3)):
        x = scale * rng.normal(size=n) + np.where(np.arange(n) >= n // 3, 1.0, 0.0)
        t, k = max_shift_statistic(x, m)
        bt, bk = brute_force(x, m)
        assert t == pytest.approx(bt) and k == bk


def test_error_model_floor_exact_zeros_make_no_change_point():
    # zeros (e.g. clipped oil-cut readings) then a 0.7 sigma offset: with the variance floor T = 0.7 / sqrt(2/15)
    x = np.r_[np.zeros(15), np.full(15, 0.7)]
    t, k = max_shift_statistic(x, 3)
    assert (t, k) == (pytest.approx(0.7 / np.sqrt(2 / 15)), 15)
    assert shift_pvalue(t, 30) > 0.05 and segment(x, 0.05) == []


def test_null_distribution_matches_closed_form_for_one_split():
    # n = 6, m = 3: one split, T = |Z| / max(1, s) with Z ~ N(0, 1) independent of 4 s^2 ~ chi^2_4
    def exact_sf(c):
        f = lambda q: 2 * norm.sf(c * max(1.0, np.sqrt(q / 4))) * chi2.pdf(q, 4)  # noqa: E731
        return integrate.quad(f, 0, 4)[0] + integrate.quad(f, 4, np.inf)[0]

    for c in (1.0, 2.0, 3.0):
        p, q = shift_pvalue(c, 6, 3, draws=20000), exact_sf(c)
        assert abs(p - q) < 4 * np.sqrt(q * (1 - q) / 20000) + 1e-4


def test_known_change_point_is_found_at_its_position():
    hits = []
    for seed in range(30):
        rng = np.random.default_rng(100 + seed)
        x = rng.normal(size=40)
        x[25:] += 3.0  # a clear shift: 3 sigma
        found = segment(x, 0.01)
        hits.append(len(found) >= 1 and min(abs(k - 25) for k, _, _ in found) <= 2)
    assert np.mean(hits) >= 0.9
    rng = np.random.default_rng(7)
    x = rng.normal(size=60)
    x[20:] += 3.0
    x[42:] -= 3.0
    assert [k for k, _, _ in segment(x, 0.001)] == [pytest.approx(20, abs=1), pytest.approx(42, abs=1)]


def test_white_noise_is_flagged_at_the_nominal_rate():
    rng = np.random.default_rng(2024)
    reps, level = 400, 0.05
    pvalues = []
    for _ in range(reps):
        x = rng.normal(size=30)
        pvalues.append(shift_pvalue(max_shift_statistic(x, 3)[0], 30))
    rejected = int(np.sum(np.array(pvalues) < level))
    assert binom.cdf(rejected, reps, level) > 0.001 and binom.sf(rejected - 1, reps, level) > 0.001
    assert kstest(pvalues, "uniform").pvalue > 0.001
    # binary segmentation: the family-wise error per series is the first test's level
    assert np.mean([bool(segment(rng.normal(size=30), level)) for _ in range(reps)]) < level + 3 * np.sqrt(
        level * (1 - level) / reps)


def test_change_points_in_a_layout_are_inside_slugs_with_their_shift():
    n = 45
    pv = (np.arange(n) + 1) * 0.1
    slug = np.searchsorted([1.5, 99.0], pv - 1e-9)  # slug boundary at 1.5 PV
    rng = np.random.default_rng(3)
    w = rng.normal(size=n) * 0.5
    w[slug == 1] += 10.0  # a jump at the slug boundary only: expected, not a change point
    block = Block("dp", "E", np.arange(n), pv, np.zeros(n), slug, BlockErrorModel(np.full(n, 100.0), 0.0))
    layout = Layout((block,))
    assert change_points(layout, w, 100.0 * w, {"E": ["A", "B"]}, 0.01) == []
    w[pv > 3.0 + 1e-9] += 4.0  # a mean shift inside slug B after 3.0 PV
    (cp,) = change_points(layout, w, 100.0 * w, {"E": ["A", "B"]}, 0.01)
    assert (cp.variable, cp.experiment, cp.slug_name) == ("dp", "E", "B")
    assert cp.pv == pytest.approx(3.05)
    assert cp.shift_whitened == pytest.approx(4.0, abs=0.6) and cp.shift == pytest.approx(100 * cp.shift_whitened)


def test_bad_input_is_rejected():
    with pytest.raises(ParameterError, match="min_segment >= 2"):
        max_shift_statistic(np.zeros(5), 3)
    with pytest.raises(ParameterError, match="allowed \\(0, 1\\)"):
        segment(np.zeros(10), 1.5)
