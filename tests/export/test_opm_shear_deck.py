"""The exported shear-thinning keywords and per-slug rates, against formulas written out here (no OPM Flow needed).

PLYSHLOG must hold, at each of its nodes, Meter's viscosity (Eq. 2.4) at UTCHEM's equivalent shear rate divided by
the zero-shear viscosity (Eqs. 2.1-2.3), with the node's water velocity converted to that shear rate by
``gamma = GAMMAC u_w[ft/day] / sqrt(k[darcy] k_rw phi S_w)`` and ``u_w = v phi (S_w - S1RWC)`` (OPM's water velocity)
at the matching saturation. WCONINJE/TSTEP carry each slug's own rate."""

import math

import numpy as np
import pytest

from spflow.core.errors import ParameterError
from spflow.export.opm_deck import write_opm_deck
from spflow.export.opm_mechanisms import OpmExportError
from spflow.export.opm_run import summary_to_series
from spflow.plugins.forward.schedule import Schedule, Slug

from .deck_text import expand, keyword_records, table

SALINITY, POLYMER_PPM = 12000.0, 1500.0
EFFECTS = {"dispersion": 0.0, "capillary_desaturation": 0.0, "shear_thinning": 1.0}
BASE = {"S1RWC": 0.22, "S2RWC": 0.28, "P1RWC": 0.15, "E1WC": 2.5, "AP1": 12.0, "AP2": 40.0, "AP3": 155.0,
        "SSLOPE": -0.6, "BETAP": 3.0, "PERM": 500.0, "PORO": 0.21, "VIS1": 0.9, "GAMMAC": 35.0, "GAMHF": 45.0,
        "POWN": 1.8, "IGAMHF": 0, "C50": SALINITY * 0.145 / 9400.0, "C60": SALINITY * 0.0097 / 9400.0}
RESIDUAL_OIL = BASE | {"SWI": 1.0 - 0.28}
SCHED = Schedule((Slug("W", 0.3, SALINITY, rate_ml_min=0.1), Slug("P", 0.8, SALINITY, 0.0, POLYMER_PPM),
                  Slug("EWF", 0.5, SALINITY, rate_ml_min=1.5)), "shear-deck")
QINJ = 0.25  # the default rate: slug P has none of its own
FT_PER_DAY_M_S = 0.3048 / 86400.0
DARCY_M2 = 9.869233e-13


def _zero_shear(c_wt):
    csep = SALINITY * 0.145 / 9400.0 + (BASE["BETAP"] - 1.0) * SALINITY * 0.0097 / 9400.0  # Eq. 2.3
    return BASE["VIS1"] * (1 + (BASE["AP1"] * c_wt + BASE["AP2"] * c_wt**2 + BASE["AP3"] * c_wt**3)
                           * csep ** BASE["SSLOPE"])


def _krw(sw, p):
    return p["P1RWC"] * ((sw - p["S1RWC"]) / (1 - p["S1RWC"] - p["S2RWC"])) ** p["E1WC"]


def _meter_rows(text, p, sw):
    v_m_day, z = np.array(table(text, "PLYSHLOG")[1:]).T  # first row: the reference concentration
    u_ft_day = v_m_day / 86400.0 * p["PORO"] * (sw - p["S1RWC"]) / FT_PER_DAY_M_S
    gamma = p["GAMMAC"] * u_ft_day / np.sqrt(p["PERM"] * 1e-3 * _krw(sw, p) * p["PORO"] * sw)
    mu0 = _zero_shear(POLYMER_PPM / 1e4)
    meter = BASE["VIS1"] + (mu0 - BASE["VIS1"]) / (1 + (gamma / p["GAMHF"]) ** (p["POWN"] - 1))
    return gamma, z * mu0, meter


@pytest.fixture(scope="module")
def residual_oil_deck(tmp_path_factory):
    return write_opm_deck(tmp_path_factory.mktemp("shear") / "CORE.DATA", SCHED, RESIDUAL_OIL, EFFECTS, cells=30,
                          pv_step=0.1, log=lambda m: None)


def test_plyshlog_is_meter_at_its_nodes(residual_oil_deck):
    text = residual_oil_deck.path.read_text()
    (ref,) = table(text, "PLYSHLOG")[:1]
    assert ref == [pytest.approx(POLYMER_PPM * 1e-3)]  # reference concentration, kg/m3
    gamma, mu, meter = _meter_rows(text, RESIDUAL_OIL, RESIDUAL_OIL["SWI"])
    np.testing.assert_allclose(mu, meter, rtol=1e-8)
    # the table spans the whole curve (multiplier ~1 at the first node, ~water at the last) on a fine log grid
    assert (mu[0] - meter[-1]) / (_zero_shear(POLYMER_PPM / 1e4) - BASE["VIS1"]) > 1 - 1e-5
    assert (meter[-1] - BASE["VIS1"]) < 1e-5 * _zero_shear(POLYMER_PPM / 1e4)
    assert np.all(np.diff(np.log10(gamma)) < 0.051) and "SHRATE" not in [ln.strip() for ln in text.splitlines()]


def test_half_shear_rate_of_eq_2_5_at_the_reference_concentration(tmp_path):
    p = RESIDUAL_OIL | {"IGAMHF": 1, "A0": -588.0, "A1": 7683.0, "A2": -12.0}
    with pytest.raises(OpmExportError, match="shear_thinning_concentration"):
        write_opm_deck(tmp_path / "A.DATA", SCHED, p, EFFECTS, cells=30, log=lambda m: None)
    deck = write_opm_deck(tmp_path / "B.DATA", SCHED, p, EFFECTS, cells=30, approximate=True, log=lambda m: None)
    csep = SALINITY * 0.145 / 9400.0 + (BASE["BETAP"] - 1.0) * SALINITY * 0.0097 / 9400.0
    ghalf = (p["A1"] * csep + p["A0"]) * math.exp(p["A2"] * POLYMER_PPM / 1e4)  # Eq. 2.5
    gamma, mu, _ = _meter_rows(deck.path.read_text(), p, p["SWI"])
    mu0 = _zero_shear(POLYMER_PPM / 1e4)
    np.testing.assert_allclose(mu, BASE["VIS1"] + (mu0 - BASE["VIS1"]) / (1 + (gamma / ghalf) ** (p["POWN"] - 1)),
                               rtol=1e-8)


def test_two_phase_is_matched_at_the_requested_saturation(tmp_path):
    p = BASE | {"SWI": 0.22}
    with pytest.raises(OpmExportError, match="shear_thinning_saturation"):
        write_opm_deck(tmp_path / "A.DATA", SCHED, p, EFFECTS, cells=30, log=lambda m: None)
    notes = []
    deck = write_opm_deck(tmp_path / "B.DATA", SCHED, p, EFFECTS, cells=30, approximate=True, shear_sw=0.6,
                          log=notes.append)
    assert any("shear_thinning_saturation" in n and "Sw* = 0.6" in n for n in notes)
    gamma, mu, meter = _meter_rows(deck.path.read_text(), p, 0.6)
    np.testing.assert_allclose(mu, meter, rtol=1e-8)


def test_shear_strength_scales_the_thinning(tmp_path):
    deck = write_opm_deck(tmp_path / "C.DATA", SCHED, RESIDUAL_OIL, EFFECTS | {"shear_thinning": 0.4}, cells=30,
                          log=lambda m: None)
    gamma, mu, meter = _meter_rows(deck.path.read_text(), RESIDUAL_OIL, RESIDUAL_OIL["SWI"])
    mu0 = _zero_shear(POLYMER_PPM / 1e4)
    np.testing.assert_allclose(mu, mu0 - 0.4 * (mu0 - meter), rtol=1e-8)


def test_no_plyshlog_without_shear(tmp_path):
    deck = write_opm_deck(tmp_path / "D.DATA", SCHED, RESIDUAL_OIL, EFFECTS | {"shear_thinning": 0.0}, cells=30,
                          log=lambda m: None)
    assert deck.shear is None and not keyword_records(deck.path.read_text(), "PLYSHLOG")


def test_well_bore_gives_the_connections_the_block_velocity(residual_oil_deck):
    """OPM's connection velocity q / (2 pi sqrt(r_e r_w) DZ phi (Sw - Swcr)) equals the blocks' q / (DY DZ phi (Sw -
    Swcr)) when sqrt(r_e r_w) = DY DZ / (2 pi DZ), r_e = sqrt(DX DY / pi)."""
    text = residual_oil_deck.path.read_text()
    (dx_rec,) = keyword_records(text, "DX")
    dx = float(expand(" ".join(dx_rec).replace("/", " ").split())[0])
    (dy_rec,) = keyword_records(text, "DY")
    dy = float(expand(" ".join(dy_rec).replace("/", " ").split())[0])
    (compdat,) = keyword_records(text, "COMPDAT")
    diameters = [float(ln.split()[8]) for ln in compdat if ln.strip() and ln.strip() != "/"]
    re = math.sqrt(dx * dy / math.pi)
    for d in diameters:
        assert 2 * math.pi * math.sqrt(re * d / 2) * dy == pytest.approx(dy * dy, rel=1e-8)


def test_each_slug_injects_at_its_own_rate(residual_oil_deck):
    deck = residual_oil_deck
    text = deck.path.read_text()
    rates = [float(body[0].split()[4]) for body in keyword_records(text, "WCONINJE")]
    steps = [sum(float(t) for t in " ".join(body).replace("/", " ").split()) for body in keyword_records(text, "TSTEP")]
    core_area = math.pi * 0.0508**2 / 4  # default DIAMETER
    expected = [q * 1e-6 / 60 * deck.area_scale * 86400 for q in (0.1, QINJ, 1.5)]  # m3/day of the scaled model
    assert rates == pytest.approx(expected, rel=1e-9)
    pore_volume = 0.1524 * core_area * deck.area_scale * RESIDUAL_OIL["PORO"]  # default LENGTH
    assert steps == pytest.approx([s.pv * pore_volume / r for s, r in zip(SCHED.slugs, expected)], rel=1e-8)


@pytest.mark.parametrize("sw", [0.22, 1.01, float("nan")])
def test_bad_matching_saturation_is_refused_before_writing(tmp_path, sw):
    with pytest.raises(ParameterError, match="shear_sw"):
        write_opm_deck(tmp_path / "E.DATA", SCHED, BASE | {"SWI": 0.22}, EFFECTS, cells=30, approximate=True,
                       shear_sw=sw, log=lambda m: None)
    assert not (tmp_path / "E.DATA").exists()


def test_a_core_without_oil_reports_zero_recovery(tmp_path):
    """A water-filled core (OOIP = 0, SWI = 1) gives recovery 0, not 0/0 (summary vectors made up here)."""
    p = RESIDUAL_OIL | {"SWI": 1.0}
    deck = write_opm_deck(tmp_path / "W.DATA", SCHED, p, EFFECTS, cells=10, log=lambda m: None)
    n = 4
    water = np.linspace(1.0, 4.0, n) * deck.pore_volume_m3 / 4.0
    summary = {"FOPT": np.zeros(n), "FOIP": np.zeros(n), "FWIT": water, "FWPT": water,
               "WBHP:INJ": np.full(n, 201.0), "WBHP:PROD": np.full(n, 200.0)}
    with np.errstate(all="raise"):
        series = summary_to_series(summary, deck)
    assert np.all(series.recovery.values == 0.0) and np.all(series.oil_cut.values == 0.0)
    np.testing.assert_allclose(series.dp.values, 1.0e5)
