"""Langmuir adsorption fit (Eqs. 2.15-2.16): isotherm vs the hand values of docs/forward_model.md, unit conversion,
recovery, coverage."""

import numpy as np
import pytest
from scipy import stats
from scipy.optimize import minimize_scalar

from spflow.core.stage import StageContext
from spflow.plugins.forward.parameters import default_params
from spflow.plugins.lab import adsorption_fit as af
from spflow.plugins.lab.fit_result import FIT, FitError, fit_interval, stated_interval
from spflow.plugins.lab.polymer_fit_figures import adsorption_figure
from spflow.plugins.lab.polymer_fit_stages import FitAdsorption

CTX = StageContext("lab", verbose=False)


def _truth(component):
    return {n: default_params()[n] for n in af.COMPONENTS[component][1]}


def test_isotherm_matches_physics_notes():
    # docs/forward_model.md, Property values: surfactant AD31 1.0, AD32 0.5, C_SE 0.3, B3D 1000, C3 0.01 -> 0.001045;
    # polymer AD41 0.7, B4D 100, C4 0.1 wt% -> 0.006364 wt%
    assert af.isotherm(0.01, 0.3, 1.0, 0.5, 1000.0) == pytest.approx(0.0010455, rel=1e-4)
    assert af.isotherm(0.1, 0.0, 0.7, 0.0, 100.0) == pytest.approx(0.0063636, rel=1e-4)


def test_retention_mg_per_g_converted_to_pore_volume_units():
    # 1 mg/g on rock of 2.65 g/cm3 and porosity 0.23: 2.65 (0.77/0.23) mg per cm3 of pore = 0.8872 wt% (x100/1000)
    ds = af.synthetic_adsorption("polymer", _truth("polymer"), None)
    fit = af.fit_adsorption(ds, "polymer")
    assert fit.attrs["pv_factor"] == pytest.approx(2.65 * 0.77 / 0.23 / 1000 * 100, rel=1e-12)
    np.testing.assert_allclose(fit["c_hat"].values, ds["adsorbed"].values * fit.attrs["pv_factor"])


@pytest.mark.parametrize("component", list(af.COMPONENTS))
def test_noise_free_data_recover_the_truth(component):
    truth = _truth(component)
    fit = af.fit_adsorption(af.synthetic_adsorption(component, truth, None), component)
    for name, value in truth.items():
        assert float(fit["estimate"].sel(param=name)) == pytest.approx(value, rel=1e-6, abs=1e-8), name
    FIT.validate(fit, stage="fit_adsorption", port="output")


@pytest.mark.parametrize("component", list(af.COMPONENTS))
def test_truth_inside_stated_95_percent_interval_over_seeds(component):
    # the stated interval is the profile-likelihood one; with a correct 95 % interval >= 16/20 holds with prob. 0.997
    truth = _truth(component)
    hits = dict.fromkeys(truth, 0)
    for seed in range(20):
        fit = af.fit_adsorption(af.synthetic_adsorption(component, truth, np.random.default_rng(3000 + seed)),
                                component)
        assert fit.attrs["stated_interval"] == "profile"
        lo, hi = stated_interval(fit)
        for name in truth:
            hits[name] += bool(lo.sel(param=name) <= truth[name] <= hi.sel(param=name))
    assert all(h >= 16 for h in hits.values()), hits


def test_profile_interval_of_a_slope_clipped_at_its_bound():
    # bundled surfactant table: AD32 is estimated at its bound 0, so its interval starts there; at the upper end the
    # RSS minimised over AD31 (closed form: the isotherm is linear in it) and B3D (minimize_scalar) equals the F
    # threshold -- computed here without least_squares
    fit = FitAdsorption(component="surfactant").run(CTX)
    assert float(fit["estimate"].sel(param="AD32")) == pytest.approx(0.0, abs=1e-20)
    assert float(fit["profile_lower"].sel(param="AD32")) == 0.0
    conc, cse, c_hat = fit["concentration"].values, fit["cse"].values, fit["c_hat"].values
    scale = np.max(np.abs(c_hat))

    def profiled(a2):
        def rss(log_b):
            g = conc / (1.0 + np.exp(log_b) * conc)
            a1 = max(0.0, np.sum(g * (c_hat - a2 * cse * g)) / np.sum(g * g))
            return np.sum(((a1 + a2 * cse) * g - c_hat) ** 2) / scale**2
        return minimize_scalar(rss, bounds=(np.log(1.0), np.log(1e4)), method="bounded",
                               options={"xatol": 1e-10}).fun

    dof = fit.attrs["dof"]
    threshold = fit.attrs["rss"] * (1 + stats.t.ppf(0.975, dof) ** 2 / dof)
    upper = float(fit["profile_upper"].sel(param="AD32"))
    assert profiled(upper) == pytest.approx(threshold, rel=1e-6)
    assert profiled(0.0) == pytest.approx(fit.attrs["rss"], rel=1e-6)
    lo, hi = fit_interval(fit)
    assert float(lo.sel(param="AD32")) < 0.0 < upper < float(hi.sel(param="AD32"))  # linearised leaves the bounds


def test_salinity_slope_is_recovered_when_present():
    # a non-zero AD42 (not Table 2.4) must be found: a = AD41 + AD42 C_SEP differs between the two brines
    truth = {"AD41": 4.0, "AD42": 20.0, "B4D": 100.0}
    fit = af.fit_adsorption(af.synthetic_adsorption("polymer", truth, None), "polymer")
    np.testing.assert_allclose(fit["estimate"].values, [4.0, 20.0, 100.0], rtol=1e-6)


@pytest.mark.parametrize("component", list(af.COMPONENTS))
def test_stage_on_bundled_data_and_figure(component, tmp_path):
    fit = FitAdsorption(component=component).run(CTX)
    truth = _truth(component)
    for name in truth:
        est, std = float(fit["estimate"].sel(param=name)), float(fit["std"].sel(param=name))
        assert abs(est - truth[name]) <= 3.5 * std, (name, est, std)
    assert adsorption_figure(fit, tmp_path / f"{component}.png").stat().st_size > 10_000


def test_bad_inputs_raise():
    ds = af.synthetic_adsorption("polymer", _truth("polymer"), None)
    with pytest.raises(FitError, match="component 'clay' is not allowed"):
        af.fit_adsorption(ds, "clay")
    bad = ds.copy()
    bad.attrs["meta_porosity"] = "1.5"
    with pytest.raises(FitError, match="porosity"):
        af.fit_adsorption(bad, "polymer")
    with pytest.raises(Exception, match="not allowed"):
        FitAdsorption(component="clay")
