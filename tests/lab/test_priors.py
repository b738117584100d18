"""The ``priors`` stage (thesis Algorithm 1 line 5, section 2.12) and the ``lab_priors`` pipeline.

The boxes are recomputed here from the fits' estimates and standard errors (±20 %, k std, clipping to the forward
model's bounds); the output must satisfy the SPACE contract and drive ``lhs_design``; bad requests fail with the
name and range; the pipeline runs every lab fit, the priors and the chapter-3 history-matching DAG at a tiny budget.
"""


import numpy as np
import pytest
import xarray as xr

import spflow
from spflow.core.errors import ParameterError
from spflow.core.stage import StageContext
from spflow.pipelines import lab_priors
from spflow.plugins.design.latin_hypercube import LatinHypercubeDesign
from spflow.plugins.design.schemas import SPACE
from spflow.plugins.design.thesis_tables import TABLE_3_2
from spflow.plugins.forward.parameters import PARAMETERS
from spflow.plugins.lab import surfactant_fit_stages
from spflow.plugins.lab.fit_result import FIT
from spflow.plugins.lab.priors import Priors
from spflow.plugins.surrogates.input_marginals import TruncatedNormal, Uniform, marginals_from_dataset

BOUNDS = {p.name: (p.lower, p.upper) for p in PARAMETERS}
CTX = StageContext("priors", verbose=False)


@pytest.fixture(scope="module")
def fits():
    """Real FIT datasets of the bundled surfactant lab tables."""
    return {
        "fit_phase_behaviour": surfactant_fit_stages.FitPhaseBehaviour().run(CTX),
        "fit_me_viscosity": surfactant_fit_stages.FitMEViscosity().run(CTX),
        "fit_desaturation": surfactant_fit_stages.FitDesaturation().run(CTX),
        "fit_ift": surfactant_fit_stages.FitIFT().run(CTX),
    }


def _fit(names, estimates, stds):
    """A minimal FIT dataset (as a lab fit would return it)."""
    cov = np.diag(np.asarray(stds, dtype=float) ** 2)
    per_param = {"units_variable": "unit"}
    ds = xr.Dataset({"estimate": ("param", np.asarray(estimates, dtype=float), per_param),
                     "std": ("param", np.asarray(stds, dtype=float), per_param),
                     "covariance": (("param", "param_"), cov, {"units_variable": "covariance_units"}),
                     "unit": ("param", np.array(["1"] * len(names))),
                     "covariance_units": (("param", "param_"), np.full((len(names), len(names)), "1"))},
                    coords={"param": list(names), "param_": list(names)},
                    attrs={"n_points": 10, "dof": 8, "rss": 1.0, "reduced_chi2": 0.1, "method": "test",
                           "kind": "test", "experiment": "test"})
    FIT.validate(ds, stage="test", port="fit")
    return ds


def _estimate(fits, name):
    for fit in fits.values():
        if name in fit["param"].values:
            return float(fit["estimate"].sel(param=name)), float(fit["std"].sel(param=name))
    raise KeyError(name)


def test_relative_box_is_plus_minus_20_percent_of_the_estimates(fits):
    names = ["HBNC70", "HBNC71", "HBNC72", "CHUH", "AHUH", "ALPHAV1", "ALPHAV2", "T22", "S2RWC", "S2RC"]
    space = Priors(names=names).run(CTX, **fits)
    SPACE.validate(space, stage="priors", port="output")
    assert list(space["param"].values) == names
    for name in names:
        est, _ = _estimate(fits, name)
        lo, hi = BOUNDS[name]
        row = space.sel(param=name)
        assert float(row.lower) == pytest.approx(max(lo, 0.8 * est), rel=1e-12)
        assert float(row.upper) == pytest.approx(min(hi, 1.2 * est), rel=1e-12)
        assert float(row.default) == est
    assert space["source"].sel(param="T22").item() == "fit_desaturation"


def test_fit_uncertainty_box_is_k_standard_errors(fits):
    names = ["CSEL", "CSEU", "HBNC71", "CHUH", "T22"]
    space = Priors(names=names, mode="fit_uncertainty", k=3.0).run(CTX, **fits)
    for name in names:
        est, std = _estimate(fits, name)
        assert float(space["lower"].sel(param=name)) == pytest.approx(est - 3 * std, rel=1e-12)
        assert float(space["upper"].sel(param=name)) == pytest.approx(est + 3 * std, rel=1e-12)


def test_boxes_are_clipped_to_the_physical_bounds():
    fit = _fit(["HBNC72", "ALPHAV3", "S2RC"], [0.45, 19.0, 0.02], [0.2, 5.0, 0.05])
    relative = Priors(names=["HBNC72", "ALPHAV3"]).run(CTX, fit_phase_behaviour=fit)
    assert float(relative["upper"].sel(param="HBNC72")) == 0.5  # 1.2 * 0.45 = 0.54 > HBNC72's bound 0.5
    assert float(relative["lower"].sel(param="HBNC72")) == pytest.approx(0.36)
    assert float(relative["upper"].sel(param="ALPHAV3")) == 20.0
    spread = Priors(names=["S2RC"], mode="fit_uncertainty").run(CTX, fit_desaturation=fit)
    assert float(spread["lower"].sel(param="S2RC")) == 0.0  # 0.02 - 2 * 0.05 < 0
    assert float(spread["upper"].sel(param="S2RC")) == pytest.approx(0.12)


def test_truncated_normal_priors_are_the_fits_normals_on_the_boxes(fits):
    """distribution='truncated_normal': N(estimate, std²) of each fit, truncated to the same box as the uniform
    priors (here k = 2 standard errors, clipped); a 'ranges' parameter stays uniform; the laws round-trip through the
    space's string variables, and the uniform default writes none."""
    names = ["CSEL", "HBNC71", "T22", "E2C"]
    space = Priors(names=names, mode="fit_uncertainty", distribution="truncated_normal",
                   ranges={"E2C": TABLE_3_2["E2C"]}).run(CTX, **fits)
    SPACE.validate(space, stage="priors", port="output")
    laws = marginals_from_dataset(space, "priors")
    for name, law in zip(names[:3], laws):
        est, std = _estimate(fits, name)
        lo, hi = max(BOUNDS[name][0], est - 2 * std), min(BOUNDS[name][1], est + 2 * std)
        assert law == TruncatedNormal(est, std, float(space["lower"].sel(param=name)),
                                      float(space["upper"].sel(param=name)))
        assert law.support == pytest.approx((lo, hi), rel=1e-12)
    assert laws[3] == Uniform(*TABLE_3_2["E2C"])
    assert "distribution" not in Priors(names=names[:3], mode="fit_uncertainty").run(CTX, **fits).variables
    with pytest.raises(ParameterError, match="AP2: the fit standard error from 'fit_polymer_rheology' is 0.0; "
                                             "distribution='truncated_normal' needs it finite and > 0"):
        Priors(names=["AP2"], distribution="truncated_normal").run(
            CTX, fit_polymer_rheology=_fit(["AP2"], [1.0], [0.0]))


def test_explicit_ranges_and_lhs_design(fits):
    space = Priors(names=["HBNC70", "E2C"], ranges={"E2C": TABLE_3_2["E2C"]}).run(CTX, **fits)
    assert [float(space["lower"].sel(param="E2C")), float(space["upper"].sel(param="E2C"))] == TABLE_3_2["E2C"]
    assert space["source"].values.tolist() == ["fit_phase_behaviour", "ranges"]
    design = LatinHypercubeDesign(samples=16, seed=1).run(CTX, space=space)
    values = design["values"].transpose("sample", "param").values
    assert np.all(values >= space["lower"].values) and np.all(values <= space["upper"].values)


def test_bad_requests_name_the_problem(fits):
    with pytest.raises(ParameterError, match="unknown forward-model parameter 'HBNC7'.*did you mean .*HBNC70"):
        Priors(names=["HBNC7"])
    with pytest.raises(ParameterError, match="'names' must be a non-empty list"):
        Priors(names=[])
    with pytest.raises(ParameterError, match="'ranges': 'E2C' is not in 'names'"):
        Priors(names=["HBNC70"], ranges={"E2C": [1.5, 3.0]})
    with pytest.raises(ParameterError, match=r"E2C = \[0, 3\] must satisfy low < high inside .*\[1, 6\]"):
        Priors(names=["E2C"], ranges={"E2C": [0.0, 3.0]})
    with pytest.raises(ParameterError, match="no wired fit estimates 'CRK'"):
        Priors(names=["CRK"]).run(CTX, **fits)
    with pytest.raises(ParameterError, match="wire at least one lab fit"):
        Priors(names=["CRK"]).run(CTX)
    with pytest.raises(ParameterError, match="T22 is estimated by both 'fit_desaturation' and 'fit_tracer'"):
        Priors(names=["T22"]).run(CTX, fit_desaturation=fits["fit_desaturation"], fit_tracer=fits["fit_desaturation"])
    # ±20 % boxes of CSEL (0.255) and CSEU (0.305) overlap: some points would have CSEL >= CSEU
    with pytest.raises(ParameterError, match="CSEL .* must satisfy CSEL < CSEU"):
        Priors(names=["CSEL", "CSEU"]).run(CTX, **fits)
    zero = _fit(["AP2"], [0.0], [1.0])
    with pytest.raises(ParameterError, match="AP2: estimate 0.0 gives an empty ±0.2 box"):
        Priors(names=["AP2"]).run(CTX, fit_polymer_rheology=zero)
    with pytest.raises(ParameterError, match="AP2: fit standard error 0.0 must be finite and > 0"):
        Priors(names=["AP2"], mode="fit_uncertainty").run(CTX, fit_polymer_rheology=_fit(["AP2"], [1.0], [0.0]))


def test_lab_priors_pipeline_feeds_history_matching(tmp_path):
    """All lab fits -> priors -> the chapter-3 DAG (its own ``space`` node replaced), tiny budget."""
    pipe = lab_priors.pipeline(front_end="history_matching", samples=10, cells=12, generations=2, population=8)
    assert pipe.nodes["history_matching.calibration"].params["generations"] == 2
    assert pipe.nodes["history_matching.design"].inputs == {"space": "space"}
    assert pipe.nodes["history_matching.calibration"].inputs["space"] == "space"
    result = spflow.run(pipe, cache=tmp_path / "cache", jobs=1, verbose=False)
    lines = lab_priors.report(result, tmp_path)
    space = result["space"]
    assert list(space["param"].values) == list(TABLE_3_2)
    for name in ("HBNC70", "HBNC71", "ALPHAV2", "AD31", "CRK", "ALPHAL1"):
        node = space["source"].sel(param=name).item()
        est = float(result[node]["estimate"].sel(param=name))
        assert float(space["lower"].sel(param=name)) == pytest.approx(0.8 * est, rel=1e-12)
        assert float(space["upper"].sel(param=name)) == pytest.approx(1.2 * est, rel=1e-12)
    for name in ("GAMHF", "E2C", "E2WC"):
        assert [float(space["lower"].sel(param=name)), float(space["upper"].sel(param=name))] == TABLE_3_2[name]
    design = result["history_matching.design"]["values"]
    assert np.all(design.min("sample") >= space["lower"]) and np.all(design.max("sample") <= space["upper"])
    calibration = result["history_matching.calibration"]
    np.testing.assert_allclose(calibration["prior_lower"].values, space["lower"].values)
    assert calibration.attrs["generations_run"] >= 1
    assert len(list(tmp_path.glob("*.png"))) == 10 and any("HBNC70" in line for line in lines)
