"""The exported OPM deck's keyword tables equal spflow's property models at their nodes.

Every expected value is computed here from the thesis formulas (Eqs. 1.6-1.8, 2.1-2.3, 2.7-2.8, 2.14-2.16) and
the documented unit conversions, not from the exporter's code. No OPM Flow needed."""

import math

import numpy as np
import pytest

from spflow.core.errors import ParameterError
from spflow.export.opm_deck import write_opm_deck
from spflow.export.opm_mechanisms import OpmExportError
from spflow.plugins.forward.schedule import Schedule, Slug

from .deck_text import expand, keyword_records, table

# exact export: mechanisms OPM has not are switched off
OFF = {"shear_thinning": 0.0, "dispersion": 0.0, "capillary_desaturation": 0.0}
PARAMS = {"S1RWC": 0.22, "S2RWC": 0.28, "P1RWC": 0.15, "P2RWC": 0.7, "E1WC": 2.5, "E2WC": 3.0, "SWI": 0.22,
          "AP1": 12.0, "AP2": 40.0, "AP3": 155.0, "SSLOPE": -0.6, "BETAP": 3.0, "AD41": 5.0, "AD42": 2.0,
          "B4D": 80.0, "BRK": 80.0, "CRK": 0.05, "EPHI4": 0.9, "PERM": 500.0, "PORO": 0.21}
SALINITY = 12000.0
PARAMS |= {"C50": SALINITY * 0.145 / 9400.0, "C60": SALINITY * 0.0097 / 9400.0}  # connate brine = injected brine
SCHED = Schedule((Slug("W", 0.4, SALINITY), Slug("P", 0.8, SALINITY, 0.0, 1500.0), Slug("EWF", 0.6, SALINITY)),
                 "deck-test")


@pytest.fixture(scope="module")
def deck(tmp_path_factory):
    path = tmp_path_factory.mktemp("deck") / "CORE.DATA"
    return write_opm_deck(path, SCHED, PARAMS, OFF, cells=40, pv_step=0.05, log=lambda m: None)


@pytest.fixture(scope="module")
def text(deck):
    return deck.path.read_text()


def _csep():
    anions = SALINITY * 0.145 / 9400.0  # Table 2.1 brine scaled linearly (units.py)
    divalent = SALINITY * 0.0097 / 9400.0
    return anions + (PARAMS["BETAP"] - 1.0) * divalent  # Eq. 2.3 with C11 = 1


def test_swof_is_the_low_nc_corey_model(text):
    rows = np.array(table(text, "SWOF"))
    sw, krw, krow, pc = rows.T
    assert sw[0] == 0.0 and sw[-1] == 1.0 and np.all(np.diff(sw) > 0)
    s1r, s2r = PARAMS["S1RWC"], PARAMS["S2RWC"]
    assert np.any(np.isclose(sw, s1r)) and np.any(np.isclose(sw, 1 - s2r))
    window = 1.0 - s1r - s2r
    sbar_w = np.clip((sw - s1r) / window, 0, 1)
    sbar_o = np.clip((1 - sw - s2r) / window, 0, 1)
    np.testing.assert_allclose(krw, PARAMS["P1RWC"] * sbar_w ** PARAMS["E1WC"], rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(krow, PARAMS["P2RWC"] * sbar_o ** PARAMS["E2WC"], rtol=1e-8, atol=1e-12)
    assert np.all(pc == 0.0)
    # linear interpolation of the table reproduces the curve between nodes to 1e-5
    s = np.linspace(s1r, 1 - s2r, 997)
    exact = PARAMS["P1RWC"] * ((s - s1r) / window) ** PARAMS["E1WC"]
    assert np.max(np.abs(np.interp(s, sw, krw) - exact)) < 1e-5


def test_plyvisc_is_flory_huggins_at_the_slug_salinity(text):
    c, mult = np.array(table(text, "PLYVISC")).T
    assert c[0] == 0.0 and math.isclose(c[-1], 1.5)  # 1500 ppm = 1.5 kg/m3
    x = c / 10.0  # wt %
    expected = 1 + (PARAMS["AP1"] * x + PARAMS["AP2"] * x**2 + PARAMS["AP3"] * x**3) * _csep() ** PARAMS["SSLOPE"]
    np.testing.assert_allclose(mult, expected, rtol=1e-9)


def test_plyads_is_langmuir_in_kg_per_kg_rock(text):
    c, ads = np.array(table(text, "PLYADS")).T
    x = c / 10.0
    a = PARAMS["AD41"] + PARAMS["AD42"] * _csep()  # Eq. 2.16 without the permeability factor
    per_pv = a * x / (1 + PARAMS["B4D"] * x)  # Eq. 2.15, wt % x PV / PV
    phi, rho = PARAMS["PORO"], 2650.0
    # mass per bulk volume: phi * 10 kg/m3 per wt % * per_pv == (1 - phi) * rho * ads
    np.testing.assert_allclose(ads * (1 - phi) * rho, phi * 10.0 * per_pv, rtol=1e-9, atol=1e-15)


def test_plyrock_dead_pore_space_rrf_and_max_adsorption(text):
    (row,) = table(text, "PLYROCK")
    ipv, rrf, rho, index, max_ads = row
    assert math.isclose(ipv, 1 - PARAMS["EPHI4"], rel_tol=1e-9)
    kd = PARAMS["PERM"] / 1000.0
    bracket = 1 - PARAMS["CRK"] * (PARAMS["AP1"] * _csep() ** PARAMS["SSLOPE"]) ** (1 / 3) / math.sqrt(
        kd / PARAMS["PORO"])
    assert math.isclose(rrf, min(bracket**-4, 10.0), rel_tol=1e-9)  # Eq. 2.8, RKCAP 10
    assert rho == 2650.0 and index == 2
    a = PARAMS["AD41"] + PARAMS["AD42"] * _csep()
    plateau = PARAMS["PORO"] * 10.0 * (a / PARAMS["B4D"]) / (rho * (1 - PARAMS["PORO"]))
    assert math.isclose(max_ads, plateau, rel_tol=1e-9)
    # hence OPM's R_k = 1 + (RRF - 1) Ca(c) / Ca_max equals Eq. 2.7 at every node
    c, ads = np.array(table(text, "PLYADS")).T
    x = c / 10.0
    np.testing.assert_allclose(1 + (rrf - 1) * ads / max_ads,
                               1 + (rrf - 1) * PARAMS["BRK"] * x / (1 + PARAMS["BRK"] * x), rtol=1e-9)


def test_grid_wells_and_schedule_scale_the_core(deck, text):
    d, length, phi = 0.0508, 0.1524, PARAMS["PORO"]
    core_area = math.pi * d**2 / 4
    (dx_rec,) = keyword_records(text, "DX")
    dx = [float(v) for v in expand(" ".join(dx_rec).replace("/", " ").split())]
    assert len(dx) == 40 and math.isclose(sum(dx), length, rel_tol=1e-9)
    (dy_rec,) = keyword_records(text, "DY")
    side = float(expand(" ".join(dy_rec).replace("/", " ").split())[0])
    scale = side**2 / core_area
    assert math.isclose(scale, deck.area_scale, rel_tol=1e-8)
    q_core = 0.25e-6 / 60 * 86400  # m3/day
    rates = [float(rec[0].split()[4]) for rec in keyword_records(text, "WCONINJE")]  # one per slug
    np.testing.assert_allclose(rates, [q_core * scale] * 3, rtol=1e-8)
    t_pv = phi * core_area * length / q_core  # days, unchanged by the scaling
    steps = keyword_records(text, "TSTEP")
    totals = [sum(float(v) for v in " ".join(rec).replace("/", " ").split()) for rec in steps]
    np.testing.assert_allclose(totals, [0.4 * t_pv, 0.8 * t_pv, 0.6 * t_pv], rtol=1e-8)
    conc = [float(rec[0].split()[1]) for rec in keyword_records(text, "WPOLYMER")]
    assert conc == [0.0, 1.5, 0.0]
    # connection factors of half a block: CF = 0.00852702 k A / (dx / 2) (METRIC Darcy constant)
    (compdat,) = keyword_records(text, "COMPDAT")
    cf = [float(line.split()[7]) for line in compdat if line.strip().startswith("'")]
    expected = 0.00852702 * PARAMS["PERM"] * side**2 / (length / 40 / 2)
    np.testing.assert_allclose(cf, [expected, expected], rtol=1e-8)


def test_capillary_pressure_goes_to_the_swof_pc_column(tmp_path):
    deck = write_opm_deck(tmp_path / "PC.DATA", SCHED, PARAMS, dict(OFF, capillary_pressure=1.0), cells=10,
                          log=lambda m: None)
    sw, _, _, pc = np.array(table(deck.path.read_text(), "SWOF")).T
    sbar = np.clip((sw - PARAMS["S1RWC"]) / (1 - PARAMS["S1RWC"] - PARAMS["S2RWC"]), 0, 1)
    factor = np.minimum(np.where(sbar > 0, sbar, 1e-300) ** (-1 / 2.0), 1000.0)  # Eq. 1.8, EPC0 = 2, capped
    np.testing.assert_allclose(pc, 5000.0 * factor / 1e5, rtol=1e-8)  # CPC0 = 5000 Pa, in bar


def test_default_model_is_refused_naming_every_missing_mechanism(tmp_path):
    with pytest.raises(OpmExportError) as info:
        write_opm_deck(tmp_path / "X.DATA", SCHED, PARAMS, None, log=lambda m: None)
    msg = str(info.value)
    for name in ("shear_thinning", "dispersion", "capillary_desaturation"):
        assert name in msg
    assert not (tmp_path / "X.DATA").exists()


def test_surfactant_and_salinity_changes_are_refused_or_approximated(tmp_path, capsys):
    sp = Schedule((Slug("W", 0.5, 9400.0), Slug("SP", 0.3, 17500.0, 6780.0, 2500.0), Slug("EWF", 0.5, 9400.0)))
    with pytest.raises(OpmExportError, match="surfactant.*salinity_dependence"):
        write_opm_deck(tmp_path / "SP.DATA", sp, None, OFF, log=lambda m: None)
    deck = write_opm_deck(tmp_path / "SP.DATA", sp, None, OFF, approximate=True)
    printed = capsys.readouterr().out
    assert "APPROXIMATION surfactant" in printed and "APPROXIMATION salinity_dependence" in printed
    assert any("surfactant dropped" in n for n in deck.notes)
    assert "APPROXIMATION surfactant" in deck.path.read_text()


def test_connate_brine_of_another_salinity_is_refused(tmp_path):
    with pytest.raises(OpmExportError, match="connate_salinity"):
        write_opm_deck(tmp_path / "C.DATA", SCHED, PARAMS | {"C50": 0.3}, OFF, log=lambda m: None)


def test_rrf_without_adsorption_is_refused(tmp_path):
    with pytest.raises(OpmExportError, match="permeability_reduction_without_adsorption"):
        write_opm_deck(tmp_path / "R.DATA", SCHED, PARAMS, dict(OFF, polymer_adsorption=0.0), log=lambda m: None)


def test_time_steps_are_capped_per_slug_by_tuning(tmp_path):
    """TSMAXZ of each slug = cap x the slug's time to inject one PV at its own rate; no TUNING without a cap."""
    d, length, phi = 0.0508, 0.1524, PARAMS["PORO"]
    rates = (0.25, 1.0, 0.125)  # ml/min
    sched = Schedule(tuple(Slug(n, pv, SALINITY, 0.0, c, q) for n, pv, c, q in
                           (("W", 0.4, 0.0, rates[0]), ("P", 0.8, 1500.0, rates[1]), ("EWF", 0.6, 0.0, rates[2]))),
                     "rates")
    notes = []
    deck = write_opm_deck(tmp_path / "C.DATA", sched, PARAMS, OFF, cells=40, pv_step=0.05, max_step_pv=0.002,
                          log=notes.append)
    text = deck.path.read_text()
    t_pv = [phi * math.pi * d**2 / 4 * length / (q * 1e-6 / 60 * 86400) for q in rates]  # days, core scale
    tuning = keyword_records(text, "TUNING")
    assert len(tuning) == 3
    record1 = [rec[0].replace("/", " ").split() for rec in tuning]
    np.testing.assert_allclose([float(r[1]) for r in record1], [0.002 * t for t in t_pv], rtol=1e-8)  # TSMAXZ
    np.testing.assert_allclose([float(r[0]) for r in record1], [0.002 * t for t in t_pv], rtol=1e-8)  # TSINIT
    # each TUNING sits in its slug, before that slug's TSTEP
    order = [ln.strip() for ln in text.splitlines() if ln.strip() in ("WCONINJE", "TUNING", "TSTEP")]
    assert order == ["WCONINJE", "TUNING", "TSTEP"] * 3
    assert any("capped at 0.002 PV" in n and "--enable-tuning=true" in n for n in notes)
    assert deck.max_step_pv == 0.002
    free = write_opm_deck(tmp_path / "F.DATA", sched, PARAMS, OFF, cells=40, pv_step=0.05, max_step_pv=None,
                          log=notes.append)
    assert keyword_records(free.path.read_text(), "TUNING") == [] and free.max_step_pv is None
    assert any("no cap on OPM's time steps" in n for n in notes)


@pytest.mark.parametrize("kwargs, match", [
    ({"cells": 2}, "cells"), ({"pv_step": 0.0}, "pv_step"), ({"area_scale": 0.5}, "area_scale"),
    ({"rock_density": -1.0}, "rock_density"), ({"params": {"PORO": 2.0}}, "PORO"),
    ({"effects": {"no_such_effect": 1.0}}, "no_such_effect"), ({"max_step_pv": 0.0}, "max_step_pv"),
    ({"max_step_pv": 2.0}, "max_step_pv"),
])
def test_bad_input_names_the_field(tmp_path, kwargs, match):
    args = {"params": PARAMS, "effects": OFF} | kwargs
    with pytest.raises(ParameterError, match=match):
        write_opm_deck(tmp_path / "B.DATA", SCHED, args.pop("params"), args.pop("effects"), log=lambda m: None,
                       **args)
