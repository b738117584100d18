"""``spflow export opm --study ... --experiment ...`` with parameter sets from a file, a calibration and a posterior.

A polymer-only study (OPM Flow has no surfactant model) is written here: one experiment whose data file is a
synthetic coreflood. Expected deck values are computed from the study's numbers by hand (grid, rates, PLYVISC's
Flory-Huggins multiplier, Eqs. 2.1-2.3), not through the exporter.
"""

import math
import os
import shutil

import numpy as np
import pytest
import xarray as xr

from spflow.cli import main
from spflow.core.errors import ParameterError
from spflow.export import export_opm
from spflow.export.opm_run import OpmRunError, run_opm
from spflow.plugins.forward.simulate import simulate
from spflow.study import load_study
from spflow.synthetic import make_coreflood

from .deck_text import expand, keyword_records, table

LENGTH, DIAMETER, PORO, PERM, SWI, QINJ, VIS2 = 0.25, 1.5 * 0.0254, 0.21, 450.0, 0.25, 0.3, 8.0
SLUGS = [{"name": "WF", "pv": 0.5, "salinity_ppm": 9400},
         {"name": "P", "pv": 0.6, "salinity_ppm": 9400, "polymer_ppm": 1200, "rate_ml_min": 0.2},
         {"name": "chase", "pv": 0.4, "salinity_ppm": 9400}]
SLUG_RATES = [QINJ, 0.2, QINJ]  # ml/min: the experiment's rate unless the slug gives its own
CELLS = 20
STUDY = f"""version = 1
[parameters.calibrated]
AP1 = [10.0, 60.0]
viscosity_cubic = {{ names = ["AP3"], range = [50.0, 300.0] }}
[parameters.fixed]
EPHI4 = 0.9
[effects]
shear_thinning = 0.0
dispersion = 0.0
capillary_desaturation = 0.0

[[experiment]]
name = "poly1"
role = "calibration"
data = "poly1.nc"
rate = "{QINJ} ml/min"
schedule = [
  {{ name = "WF", pv = 0.5, salinity_ppm = 9400 }},
  {{ name = "P", pv = 0.6, salinity_ppm = 9400, polymer_ppm = 1200, rate_ml_min = 0.2 }},
  {{ name = "chase", pv = 0.4, salinity_ppm = 9400 }},
]
[experiment.core]
length = "{LENGTH} m"
diameter = "1.5 in"
porosity = "{PORO}"
permeability = "{PERM} mD"
swi = "{SWI}"
[experiment.fluids]
VIS2 = "{VIS2} cP"
"""


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    root = tmp_path_factory.mktemp("study")
    truth = {"LENGTH": LENGTH, "DIAMETER": DIAMETER, "PORO": PORO, "PERM": PERM, "SWI": SWI, "QINJ": QINJ,
             "VIS2": VIS2}
    make_coreflood({"name": "poly1", "slugs": SLUGS}, truth, cells=CELLS, pv_step=0.01).to_netcdf(root / "poly1.nc")
    (root / "study.toml").write_text(STUDY)
    return root


def _multiplier(c_kg_m3, ap1, ap3, ap2=0.0):
    """mu_p0 / mu_w of Eqs. 2.1-2.3 at 9400 ppm: C_SEP = 0.145 meq/ml, SSLOPE = -0.76 (defaults), Cp in wt%."""
    x = c_kg_m3 / 10.0
    return 1.0 + (ap1 * x + ap2 * x**2 + ap3 * x**3) * 0.145 ** -0.76


def _single(text, keyword):
    (body,) = keyword_records(text, keyword)
    return expand(" ".join(body).replace("/", " ").split())


def _export(study, out, *extra):
    return main(["export", "opm", "--study", str(study / "study.toml"), "--experiment", "poly1", "--out", str(out),
                 "--cells", str(CELLS), *extra])


def test_deck_of_a_study_experiment_carries_its_core_rates_and_fluids(study, capsys):
    out = study / "defaults"
    assert _export(study, out) == 0
    printed = capsys.readouterr().out
    text = (out / "CORE.DATA").read_text()
    dx, dy, dz = (np.array(_single(text, k), dtype=float) for k in ("DX", "DY", "DZ"))
    assert len(dx) == CELLS and np.allclose(dx, LENGTH / CELLS, rtol=1e-9)
    area = dy[0] * dz[0]
    core_area = math.pi * DIAMETER**2 / 4.0
    np.testing.assert_allclose(np.array(_single(text, "PORO"), dtype=float), PORO)
    for k in ("PERMX", "PERMY", "PERMZ"):
        np.testing.assert_allclose(np.array(_single(text, k), dtype=float), PERM)
    # every slug's rate scaled like the cross-section: m3/day per m2 of the deck = the core's Darcy velocity
    rates = [float(expand(body[0].split())[4]) for body in keyword_records(text, "WCONINJE")]
    darcy = [q * 1e-6 * 1440.0 / core_area for q in SLUG_RATES]  # ml/min over the core's section, m/day
    np.testing.assert_allclose(np.array(rates) / area, darcy, rtol=1e-9)
    c, mult = np.array(table(text, "PLYVISC")).T
    assert c[-1] == pytest.approx(1.2)  # 1200 ppm
    np.testing.assert_allclose(mult, _multiplier(c, 15.0, 155.0), rtol=1e-9)  # AP1, AP3 defaults (Table 2.4)
    np.testing.assert_allclose(np.array(table(text, "PVDO"))[1, 2], VIS2)
    assert float(_single(text, "PLYROCK")[0]) == pytest.approx(1.0 - 0.9)  # dead pore space 1 - EPHI4 (fixed)
    # every value is printed with its source and written into the header
    for line in (f"parameter PERM = {PERM:g} mD from study", "parameter EPHI4 = 0.9 ", "from study",
                 "experiment 'poly1'", "parameter VIS2 = 8 cP", "effect shear_thinning = 0 from study",
                 "schedule 'poly1' from study"):
        assert line in printed and line in text, line


def _calibration_file(path, best):
    """A minimal Dataset with the nsga2_calibration stage's schema for what the exporter reads."""
    names = ["AP1", "viscosity_cubic"]
    ds = xr.Dataset({"confidence_best": ("param", np.array(best)),
                     "confidence_lower": ("param", np.array(best) - 1.0),
                     "confidence_upper": ("param", np.array(best) + 1.0),
                     "designs": (("pareto", "param"), np.array([best, [11.0, 60.0]]))},
                    coords={"param": names, "param_unit": ("param", ["(wt%)^-1", "(wt%)^-3"])},
                    attrs={"confidence_chi2_min": 41.5})
    ds.to_netcdf(path)
    return path


def test_calibration_best_point_goes_into_the_deck(study, capsys):
    cal = _calibration_file(study / "calibration.nc", [37.5, 210.0])
    out = study / "calibrated"
    assert _export(study, out, "--calibration", str(cal)) == 0
    printed = capsys.readouterr().out
    text = (out / "CORE.DATA").read_text()
    c, mult = np.array(table(text, "PLYVISC")).T
    np.testing.assert_allclose(mult, _multiplier(c, 37.5, 210.0), rtol=1e-9)  # the label maps to AP3
    assert "parameter AP1 = 37.5" in printed and "confidence_best" in printed and "chi2 = 41.5" in printed
    assert "parameter AP3 = 210" in text


def _posterior_file(path):
    rng = np.random.default_rng(7)
    theta = np.stack([rng.uniform(12.0, 50.0, (2, 5)), rng.uniform(60.0, 280.0, (2, 5))], axis=-1)
    xr.Dataset({"theta": (("chain", "draw", "param"), theta)},
               coords={"chain": [0, 1], "draw": np.arange(5), "param": ["AP1", "AP3"]}).to_netcdf(path)
    return theta


@pytest.mark.parametrize("draw", ["3", "7", "mean"])
def test_posterior_draw_or_mean_goes_into_the_deck(study, draw, capsys):
    theta = _posterior_file(study / "posterior.nc")
    out = study / f"posterior_{draw}"
    assert _export(study, out, "--posterior", str(study / "posterior.nc"), "--draw", draw) == 0
    printed = capsys.readouterr().out
    expected = theta.mean(axis=(0, 1)) if draw == "mean" else theta[int(draw) // 5, int(draw) % 5]
    c, mult = np.array(table((out / "CORE.DATA").read_text(), "PLYVISC")).T
    np.testing.assert_allclose(mult, _multiplier(c, *expected), rtol=1e-9)
    assert ("posterior mean of 10 draws" if draw == "mean" else f"chain {int(draw) // 5}, draw {int(draw) % 5}") \
        in printed


def test_bad_draw_is_refused_with_the_range(study, capsys):
    _posterior_file(study / "posterior.nc")
    assert _export(study, study / "bad", "--posterior", str(study / "posterior.nc"), "--draw", "10") == 2
    err = capsys.readouterr().err
    assert "[0, 9]" in err and "posterior.nc" in err
    assert not (study / "bad" / "CORE.DATA").exists()


def test_params_and_calibration_giving_one_parameter_clash(study, capsys):
    cal = _calibration_file(study / "calibration.nc", [37.5, 210.0])
    (study / "p.toml").write_text("AP1 = 20.0\n")
    assert _export(study, study / "clash", "--params", str(study / "p.toml"), "--calibration", str(cal)) == 2
    err = capsys.readouterr().err
    assert "'AP1'" in err and "p.toml" in err and "calibration.nc" in err
    assert not (study / "clash").exists()


def test_explicit_values_override_the_study_and_say_so(study, capsys):
    (study / "perm.toml").write_text("PERM = 600.0\n")
    out = study / "override"
    assert _export(study, out, "--params", str(study / "perm.toml"), "--effect", "dispersion=0") == 0
    printed = capsys.readouterr().out
    text = (out / "CORE.DATA").read_text()
    np.testing.assert_allclose(np.array(_single(text, "PERMX"), dtype=float), 600.0)
    override = [ln for ln in printed.splitlines() if ln.startswith("OVERRIDE PERM")]
    assert len(override) == 1 and "perm.toml" in override[0] and "450" in override[0] and "poly1" in override[0]
    assert override[0] in text


def test_python_function_and_missing_inputs(study, capsys):
    deck = export_opm(study / "py", study=study / "study.toml", experiment="poly1", params={"AP1": 25.0},
                      cells=CELLS, log=lambda line: None)
    c, mult = np.array(table(deck.path.read_text(), "PLYVISC")).T
    np.testing.assert_allclose(mult, _multiplier(c, 25.0, 155.0), rtol=1e-9)
    with pytest.raises(ParameterError, match="--experiment"):
        export_opm(study / "x", study=study / "study.toml")
    with pytest.raises(ParameterError, match="no schedule"):
        export_opm(study / "x", params={"AP1": 25.0})
    with pytest.raises(ParameterError, match="not both"):
        export_opm(study / "x", study=study / "study.toml", experiment="poly1", calibration=study / "c.nc",
                   posterior=study / "p.nc", draw=1)
    with pytest.raises(ParameterError, match="confidence_best.*version 3"):
        xr.Dataset({"designs": (("pareto", "param"), np.ones((1, 1)))}, coords={"param": ["AP1"]}).to_netcdf(
            study / "old.nc")
        export_opm(study / "x", study=study / "study.toml", experiment="poly1", calibration=study / "old.nc")


def test_a_calibration_of_other_parameters_is_noted(study):
    xr.Dataset({"confidence_best": ("param", [30.0, 0.05])},
               coords={"param": ["AP1", "HBNC70"]}).to_netcdf(study / "other.nc")
    printed = []
    export_opm(study / "other", study=study / "study.toml", experiment="poly1", calibration=study / "other.nc",
               cells=CELLS, log=printed.append)
    notes = [ln for ln in printed if ln.startswith("NOTE")]
    assert len(notes) == 2
    assert "['HBNC70']" in notes[0] and "does not calibrate" in notes[0]
    assert "['AP3']" in notes[1] and "other.nc" in notes[1]


# --- the calibrated deck in OPM Flow -------------------------------------------------------------------------------

needs_flow = pytest.mark.skipif(shutil.which("flow") is None,
                                reason="OPM Flow ('flow') is not on PATH: apt-get install libopm-simulators-bin")
#: the oleic Corey exponent of the quick history match's best point (docs/opm.md); with OPM's default 20 Newton
#: iterations it shuts the injector of this flood in the waterflood
E2WC = 2.14


@needs_flow
def test_a_calibrated_corey_exponent_runs_in_opm_flow(study):
    """Issue 21's acceptance at 100 cells, first-order spflow: recovery at the end within 0.005, Δp at every slug's
    end within 2 %."""
    deck = export_opm(study / "e2wc", study=study / "study.toml", experiment="poly1", params={"E2WC": E2WC},
                      cells=100, log=lambda line: None)
    opm = run_opm(deck)
    ref = simulate(deck.schedule, deck.params, cells=100, effects=load_study(study / "study.toml").effects,
                   scheme="upwind", pv_step=0.01)
    assert abs(float(opm.recovery[-1]) - float(ref.recovery[-1])) <= 0.005
    for end in np.cumsum([s["pv"] for s in SLUGS]):
        i = int(np.argmin(np.abs(opm.pv.values - end)))
        assert abs(opm.pv.values[i] - end) < 1e-4
        assert opm.dp.values[i] == pytest.approx(np.interp(opm.pv.values[i], ref.pv.values, ref.dp.values), rel=0.02)


@needs_flow
def test_a_well_opm_flow_shuts_is_an_error(study, tmp_path, monkeypatch):
    """The same deck with OPM's own time steps (no cap: the steps that failed) and OPM's default 20 Newton iterations
    (a wrapper around the real ``flow``) shuts the injector; the run is refused instead of returning the shut well's
    pressures."""
    wrapper = tmp_path / "flow"
    wrapper.write_text(f'#!/bin/bash\nexec {shutil.which("flow")} '
                       '"${@/--newton-max-iterations=40/--newton-max-iterations=20}"\n')
    wrapper.chmod(0o755)
    monkeypatch.setenv("PATH", f"{tmp_path}:{os.environ['PATH']}")
    deck = export_opm(study / "e2wc_shut", study=study / "study.toml", experiment="poly1", params={"E2WC": E2WC},
                      cells=100, max_step_pv=None, log=lambda line: None)
    with pytest.raises(OpmRunError, match="shut a well.*INJ"):
        run_opm(deck)
