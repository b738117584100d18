"""The ``pce`` and ``surrogate_validation`` stages on synthetic responses with known answers: exact polynomial
responses are reproduced, validation metrics equal hand computations for any surrogate kind, and bad inputs fail
with clear errors before any fitting."""

import numpy as np
import pytest
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.core.stage import StageContext
from spflow.plugins.forward.stage import RESPONSE_UNITS, RESPONSES
from spflow.plugins.surrogates.contract import SURROGATE, Surrogate, load_surrogate
from spflow.plugins.surrogates.pce_stage import PCEStage
from spflow.plugins.surrogates.validation import VALIDATION, SurrogateValidation

from surrogate_kind_plugin import surrogate_kinds_registered

CTX = StageContext(node="test", verbose=False)
NAMES = ["AD31", "HBNC71"]
LOWER, UPPER = np.array([0.0, 0.01]), np.array([2.0, 0.02])
PV = np.array([0.0, 0.5, 1.0, 1.5])


def _space():
    return xr.Dataset({"lower": ("param", LOWER, {"units": "per-parameter"}),
                       "upper": ("param", UPPER, {"units": "per-parameter"}),
                       "default": ("param", (LOWER + UPPER) / 2, {"units": "per-parameter"}),
                       "unit": ("param", ["1", "1"])}, coords={"param": NAMES})


def _design(x, names=NAMES):
    return xr.Dataset({"values": (("sample", "param"), x, {"units": "per-parameter"})},
                      coords={"sample": np.arange(len(x)), "param": names})


def _truth(x):
    """Quadratic responses (sample, experiment, pv); BCF2 ends at 1.0 PV (NaN padding after)."""
    a, b = x[:, 0][:, None, None], (x[:, 1][:, None, None] - 0.015) * 100
    pv = PV[None, None, :]
    exp = np.array([1.0, 2.0])[None, :, None]
    base = 1 + (a * exp + b**2 - a * b) * pv  # constant at pv = 0
    out = {name: base * (k + 1) for k, name in enumerate(RESPONSE_UNITS)}
    for v in out.values():
        v[:, 1, -1] = np.nan
    return out


def _responses(x):
    data = _truth(x)
    ds = xr.Dataset({name: (("sample", "experiment", "pv"), v, {"units": RESPONSE_UNITS[name]})
                     for name, v in data.items()} | {"total_pv": ("experiment", [1.5, 1.0], {"units": "1"})},
                    coords={"sample": np.arange(len(x)), "experiment": ["BCF1", "BCF2"], "pv": PV})
    RESPONSES.validate(ds, stage="test", port="responses")
    return ds


def _points(n, seed):
    return np.random.default_rng(seed).uniform(LOWER, UPPER, (n, 2))


@pytest.fixture(scope="module")
def fitted():
    x = _points(30, 0)
    stage = PCEStage(variables=["dp", "recovery"], experiments=["BCF1", "BCF2"], degree_max=3, solver="lars")
    return stage.run(CTX, space=_space(), design=_design(x), responses=_responses(x))


def test_pce_stage_reproduces_polynomial_responses(fitted):
    SURROGATE.validate(fitted, stage="test", port="out")
    assert fitted.attrs["surrogate"] == "pce" and fitted.attrs["n_train"] == 30
    assert fitted.sizes["output"] == 2 * (4 + 3)  # two variables; BCF2's padded 1.5 PV column dropped
    assert fitted.attrs["loo_mean"] < 1e-20 and fitted.attrs["modified_loo_mean"] >= fitted.attrs["loo_mean"]
    x = _points(20, 1)
    v = SurrogateValidation().run(CTX, surrogate=fitted, design=_design(x), responses=_responses(x))
    VALIDATION.validate(v, stage="test", port="out")
    ok = ~np.isnan(v["r2"].values)
    assert ok.sum() == 10  # the pv = 0 column of each variable and experiment is constant (R2 undefined)
    np.testing.assert_allclose(v["r2"].values[ok], 1.0, atol=1e-12)
    np.testing.assert_allclose(v["r2_final"].values, 1.0, atol=1e-12)
    assert v.attrs["moments"] == "analytic"
    # PCE moments are exact, so the L2 errors are the sampling error of the 20-point means: compute it here
    truth = _truth(x)["dp"][:, 0, :]
    model = load_surrogate(fitted)
    cols = model.outputs.columns("dp", "BCF1")
    expected = np.linalg.norm(truth.mean(0) - model.moments()[0][cols]) / np.linalg.norm(truth.mean(0))
    got = v["mean_l2_error"].values[(v["qoi_variable"] == "dp") & (v["qoi_experiment"] == "BCF1")][0]
    assert got == pytest.approx(expected, rel=1e-10)


class _ConstantProxy(Surrogate):
    """A toy kind (no moments()): predicts a fixed vector everywhere, to test validation of arbitrary kinds."""

    kind = "test_constant"

    def __init__(self, names, lower, upper, outputs, level):
        super().__init__(names, lower, upper, outputs)
        self.level = np.asarray(level, dtype=float)

    def _predict(self, x):
        return np.tile(self.level, (x.shape[0], 1)), np.zeros((x.shape[0], self.level.size))

    def to_dataset(self):
        return self._dataset({"level": ("output", self.level, {"units": "output units"})})

    @classmethod
    def from_dataset(cls, ds):
        return cls(**cls._common(ds), level=ds["level"].values)


@pytest.fixture(autouse=True, scope="module")
def toy_kind_registered():
    with surrogate_kinds_registered(_ConstantProxy, name="test_pce_stages_kind"):
        yield


def test_validation_works_for_any_kind(fitted):
    outputs = load_surrogate(fitted).outputs
    level = np.linspace(1.0, 2.0, len(outputs))
    toy = _ConstantProxy(NAMES, LOWER, UPPER, outputs, level).to_dataset()
    x = _points(25, 2)
    v = SurrogateValidation().run(CTX, surrogate=toy, design=_design(x), responses=_responses(x))
    assert v.attrs["surrogate"] == "test_constant" and v.attrs["moments"] == "sample moments of the predicted mean"
    truth = _truth(x)["recovery"][:, 1, :3]  # BCF2, pv 0, 0.5, 1.0
    cols = outputs.columns("recovery", "BCF2")
    r2 = 1 - np.sum((truth - level[cols]) ** 2, axis=0)[1:] / np.sum((truth - truth.mean(0)) ** 2, axis=0)[1:]
    np.testing.assert_allclose(v["r2"].values[cols][1:], r2, rtol=1e-12)
    assert np.isnan(v["r2"].values[cols][0])  # pv = 0 is constant
    sel = (v["qoi_variable"] == "recovery") & (v["qoi_experiment"] == "BCF2")
    assert v["variance_l2_error"].values[sel][0] == pytest.approx(1.0)  # a constant proxy has zero variance
    expected = np.linalg.norm(truth.mean(0) - level[cols]) / np.linalg.norm(truth.mean(0))
    assert v["mean_l2_error"].values[sel][0] == pytest.approx(expected, rel=1e-12)
    r2_max = 1 - np.sum((truth.max(1) - level[cols].max()) ** 2) / np.sum((truth.max(1) - truth.max(1).mean()) ** 2)
    assert v["r2_max"].values[sel][0] == pytest.approx(r2_max, rel=1e-12)


def test_bad_params_fail_at_construction():
    with pytest.raises(ParameterError, match="variables"):
        PCEStage(variables=["pressure"])
    with pytest.raises(ParameterError, match="degree_max"):
        PCEStage(degree_max=0)
    with pytest.raises(ParameterError, match="degree_max"):
        PCEStage(degree_max=21)
    with pytest.raises(ParameterError, match="solver"):
        PCEStage(solver="bcs")
    with pytest.raises(ParameterError, match="q"):
        PCEStage(q=0.0)
    with pytest.raises(ParameterError, match="without repeats"):
        PCEStage(experiments=[])


def test_bad_inputs_fail_before_fitting(fitted):
    x = _points(10, 3)
    stage = PCEStage(experiments=["BCF1"])
    with pytest.raises(ParameterError, match="must be exactly"):
        stage.run(CTX, space=_space(), design=_design(x[:, :1], names=["AD31"]), responses=_responses(x))
    with pytest.raises(ParameterError, match="must be exactly"):
        stage.run(CTX, space=_space(), design=_design(x, names=["AD31", "CRK"]), responses=_responses(x))
    with pytest.raises(ParameterError, match="samples"):
        stage.run(CTX, space=_space(), design=_design(x), responses=_responses(x[:9]))
    with pytest.raises(ParameterError, match="outside the box"):
        stage.run(CTX, space=_space(), design=_design(x * 2), responses=_responses(x))
    with pytest.raises(ParameterError, match="unknown experiment"):
        PCEStage(experiments=["BCF3"]).run(CTX, space=_space(), design=_design(x), responses=_responses(x))
    with pytest.raises(ParameterError, match="design's parameters"):
        SurrogateValidation().run(CTX, surrogate=fitted, design=_design(x, names=["AD31", "CRK"]),
                                  responses=_responses(x))


def test_pce_stage_reports_the_degrees_it_tries():
    x = _points(30, 0)
    reports = []
    ctx = StageContext(node="pce", verbose=False, report=lambda *report: reports.append(report))
    PCEStage(variables=["dp"], experiments=["BCF1"], degree_max=3, solver="ols").run(
        ctx, space=_space(), design=_design(x), responses=_responses(x))
    assert reports[0] == ("pce", 1, 3, "degrees") and reports[-1] == ("pce", 3, 3, "degrees")


def test_pce_stage_cross_validates_on_request():
    """Exact quadratic responses: every fold's fit (24 of the 30 runs) reproduces them, so the 5-fold error of the
    whole fit is zero to round-off, and it is what the stored model reports; the folds' fits report no progress."""
    x = _points(30, 0)
    reports = {0: [], 5: []}
    for folds in reports:
        ctx = StageContext(node="pce", verbose=False, report=lambda *report, f=folds: reports[f].append(report))
        ds = PCEStage(variables=["dp"], experiments=["BCF1"], degree_max=3, solver="ols", cv_folds=folds).run(
            ctx, space=_space(), design=_design(x), responses=_responses(x))
    assert ds.attrs["error_estimate"] == "kfold_cv" and ds.attrs["cv_folds"] == 5
    assert np.all(ds["cv_error"].values < 1e-20)
    model = load_surrogate(ds)
    assert np.array_equal(model.predict(x[:2])[1], np.broadcast_to(ds["cv_error"].values * ds["output_variance"].values,
                                                                   (2, ds.sizes["output"])))
    assert reports[5] == reports[0]
    with pytest.raises(ParameterError, match=r"cv_folds = 31 exceeds the N = 30 training runs"):
        PCEStage(variables=["dp"], experiments=["BCF1"], cv_folds=31).run(
            CTX, space=_space(), design=_design(x), responses=_responses(x))
