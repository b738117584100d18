"""Salinity scan of a tertiary SP flood through the Winsor II(-) / III / II(+) regimes (docs/forward_model.md,
Verification: test_salinity_scan.py).

The core starts at the waterflood residual (S_w = 1 - S2RWC, no mobile oil); one SP slug, a polymer drive and a
water post-flush are injected, all at the scanned salinity (also the connate brine's), so that the effective
salinity is uniform. Expected (Healy-Reed behaviour of the Hand's-rule/Chun-Huh model): the controlling IFT of the
two-/three-phase cells is smallest, and the recovery largest, at the optimal salinity C_SEOP = (CSEL + CSEU)/2; at
C_SEOP the microemulsion sits at the invariant point with R13 = R23 = (1 - C3max1)/(2 C3max1), whose IFT
sigma* is computed here independently from Eqs. 2.9-2.10.
"""

import math

import numpy as np
import pytest

from spflow.plugins.forward import units
from spflow.plugins.forward.parameters import default_params
from spflow.plugins.forward.simulate import simulate

P0 = default_params()
CSEOP = 0.5 * (P0["CSEL"] + P0["CSEU"])
FRACTIONS = (0.5, 0.8, 0.92, 1.0, 1.08, 1.2, 1.6)  # C_SE / C_SEOP: II(-), II(-), III, III, III, II(+), II(+)


def _scan_run(fraction):
    cse = fraction * CSEOP
    ppm = cse / units.ANIONS_PER_PPM
    slugs = [
        {"name": "SP", "pv": 0.5, "salinity_ppm": ppm, "surfactant_ppm": 6780.0, "polymer_ppm": 1000.0},
        {"name": "P", "pv": 0.5, "salinity_ppm": ppm, "polymer_ppm": 1000.0},
        {"name": "W", "pv": 1.0, "salinity_ppm": ppm},
    ]
    params = {"SWI": 1.0 - P0["S2RWC"], "C50": units.tds_ppm_to_anions(ppm), "C60": units.tds_ppm_to_divalent(ppm)}
    return simulate(slugs, params, cells=40, pv_step=0.05, profiles_at=np.arange(0.1, 1.01, 0.1))


@pytest.fixture(scope="module")
def scan():
    return {f: _scan_run(f) for f in FRACTIONS}


def _median_controlling_ift(ds):
    two_phase = (ds.sme.values > 1e-6) & (ds.sme.values < 1.0 - 1e-9)
    return float(np.median(ds.ift.values[two_phase]))


def test_regimes_cover_types_ii_minus_iii_ii_plus():
    lo, hi = P0["CSEL"] / CSEOP, P0["CSEU"] / CSEOP
    assert sum(f < lo for f in FRACTIONS) >= 2
    assert sum(lo <= f <= hi for f in FRACTIONS) >= 3
    assert sum(f > hi for f in FRACTIONS) >= 2


def test_recovery_is_highest_at_optimal_salinity(scan):
    final = {f: float(ds.recovery[-1]) for f, ds in scan.items()}
    best = max(final, key=final.get)
    assert best == 1.0, final
    assert final[1.0] > final[0.5] + 0.2 and final[1.0] > final[1.6] + 0.05


def test_ift_minimum_at_optimal_salinity_equals_sigma_star(scan):
    ift = {f: _median_controlling_ift(ds) for f, ds in scan.items()}
    assert min(ift, key=ift.get) == 1.0, ift
    # sigma* from Eqs. 2.9-2.10 at the type III invariant point (independent of the simulator)
    c3 = P0["HBNC71"]
    r = (1.0 - c3) / (2.0 * c3)
    c_m = ((1.0 - c3) / 2.0, (1.0 - c3) / 2.0, c3)
    dist = math.sqrt(c_m[0] ** 2 + (1.0 - c_m[1]) ** 2 + c_m[2] ** 2)  # excess oil (0, 1, 0) vs ME
    f = (1.0 - math.exp(-dist)) / (1.0 - math.exp(-math.sqrt(2.0)))
    a, c, sigma_ow = P0["AHUH"], P0["CHUH"], 10.0 ** P0["XIFTW"]
    sigma_star = sigma_ow * math.exp(-a * r) + c * f / r**2 * (1.0 - math.exp(-a * r**3))
    assert ift[1.0] == pytest.approx(sigma_star, rel=1e-9)
    assert ift[0.5] > 100.0 * sigma_star and ift[1.6] > 10.0 * sigma_star
