"""Coreflood signatures on series with known answers, and the predictive p-values."""

import numpy as np
import pytest

from spflow.plugins.gap.observed import load_experiments
from spflow.plugins.gap.signatures import predictive_pvalues, signatures


@pytest.fixture(scope="module")
def bcf1():
    return load_experiments(["BCF1"], 0.1)[0]  # slugs IWF 1.45, SP 0.5, P 1.01, EWF 1.27 PV


def test_signatures_of_constructed_series(bcf1):
    pv = bcf1.pv
    ends = bcf1.slug_ends()
    oil = np.where(pv < 0.3, 1.0, 0.0)
    oil[(pv > 0.25) & (pv < 0.35)] = 0.6                     # 0.6 at 0.3, 0 at 0.4: 0.5 at 0.3 + 0.1 / 6
    oil[(pv > 2.35) & (pv < 2.65)] = 0.3                     # oil bank from 2.4 PV (0 before): 0.05 at 2.3 + 0.1/6
    dp = np.select([pv <= ends[0], pv <= ends[1], pv <= ends[2]], [1000.0, 5000.0, 20000.0], 1500.0)
    rec = np.minimum(pv / 4.0, 1.0)
    sig = signatures(bcf1, {"oil_cut": oil, "dp": dp, "recovery": rec})
    assert sig["water_breakthrough"] == pytest.approx(0.3 + 0.1 / 6)
    assert sig["oil_bank"] == pytest.approx(2.3 + 0.1 * 0.05 / 0.3)
    assert sig["plateau_dp:SP"] == 5000.0 and sig["plateau_dp:P"] == 20000.0
    assert sig["rrf"] == pytest.approx(1.5)
    assert sig["incremental_recovery:SP"] == pytest.approx(0.5 / 4.0)
    assert sig["incremental_recovery:IWF"] == pytest.approx(1.45 / 4.0)
    assert signatures(bcf1, {}) == {}


def test_predictive_pvalues(bcf1):
    rng = np.random.default_rng(0)
    dp = 1000.0 + rng.normal(size=bcf1.pv.size)
    reps = [{"dp": 1000.0 + rng.normal(size=bcf1.pv.size)} for _ in range(99)]
    inside = predictive_pvalues(bcf1, {"dp": dp}, reps)
    far = predictive_pvalues(bcf1, {"dp": dp + 50.0}, reps)
    assert all(p > 0.001 for _, p in inside.values() if np.isfinite(p))
    # above all 99 replicates: P(T_rep >= T_obs) = 1 / 100, two-sided 2 / 100
    assert far["plateau_dp:IWF"][1] == pytest.approx(2 / 100)
    assert far["plateau_dp:IWF"][0] == pytest.approx(inside["plateau_dp:IWF"][0] + 50.0)
