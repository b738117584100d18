"""``nsga2_calibration`` with several training corefloods and the undetermined-parameter warning (issue 19): each
objective is the sum over the training corefloods of Eq. 3.16 (computed here from a linear surrogate's coefficients),
and a parameter whose noise-consistent range covers at least 90 % of its prior width is named with a warning."""

import numpy as np
import xarray as xr

from spflow.core.stage import StageContext
from spflow.plugins.calibration.nsga2_problem import SurrogateMisfitProblem
from spflow.plugins.calibration.nsga2_stage import NSGA2Calibration
from spflow.plugins.design.parameter_space import ParameterSpace
from spflow.plugins.forward.simulate import common_grid
from spflow.plugins.observations import Observations
from spflow.plugins.surrogates.outputs import OutputIndex

from test_nsga_stage import TABLE_3_2, LinearSurrogate
from test_nsga_stage import toy_kind_registered  # noqa: F401  (autouse fixture: registers the toy surrogate kind)

CTX = StageContext("test", verbose=False)


def test_objectives_sum_the_half_squared_misfits_over_the_training_corefloods():
    space = ParameterSpace(names=list(TABLE_3_2), ranges=TABLE_3_2).run(CTX)
    obs = Observations().run(CTX)
    variables, experiments, pvs = [], [], []
    for e in ("BCF1", "BCF2"):
        pv = common_grid([float(obs["total_pv"].sel(experiment=e))], 0.1)[0]
        for v in ("recovery", "dp"):
            variables += [v] * pv.size
            experiments += [e] * pv.size
            pvs += list(pv)
    index = OutputIndex(np.array(variables), np.array(experiments), np.array(pvs), {"recovery": "1", "dp": "Pa"})
    rng = np.random.default_rng(1)
    intercept = np.where(index.variable == "dp", 2e4, 0.4) * (1 + 0.1 * rng.standard_normal(len(index)))
    slopes = np.where(index.variable == "dp", 3e3, 0.05) * rng.standard_normal((9, len(index)))
    lo, hi = space["lower"].values, space["upper"].values
    surrogate = LinearSurrogate(list(space["param"].values), lo, hi, index, intercept, slopes)
    problem = SurrogateMisfitProblem(surrogate, obs, list(space["param"].values), lo, hi, ["recovery", "dp"],
                                     ["BCF1", "BCF2"])
    x = lo + (hi - lo) * rng.random((7, 9))
    prediction = intercept + (2 * (x - lo) / (hi - lo) - 1) @ slopes
    expected = np.zeros((7, 2))
    for k, v in enumerate(("recovery", "dp")):
        for e in ("BCF1", "BCF2"):
            cols = np.flatnonzero((index.variable == v) & (index.experiment == e))
            y = obs[v].sel(experiment=e).sel(pv=index.pv[cols], method="nearest").values
            keep = np.isfinite(y)
            expected[:, k] += 0.5 * np.sum((prediction[:, cols[keep]] - y[keep]) ** 2, axis=1)
    np.testing.assert_allclose(problem.objectives(x), expected, rtol=1e-12)


def test_parameters_left_undetermined_are_named_with_a_warning():
    stage = NSGA2Calibration(training=["BCF1"], held_out=["BCF2", "BCF3"])
    prior = np.array([[0.0, 3.0], [0.01, 0.02], [55.0, 100.0]])
    confidence = np.array([[0.1, 2.9], [0.0104, 0.0196], [60.0, 70.0]])  # 93 %, 92 %, 22 % of the prior width
    ds = xr.Dataset({"prior_lower": ("param", prior[:, 0]), "prior_upper": ("param", prior[:, 1]),
                     "confidence_lower": ("param", confidence[:, 0]), "confidence_upper": ("param", confidence[:, 1])},
                    coords={"param": ["ALPHAV2", "HBNC71", "GAMHF"]})
    out = stage._add_undetermined(ds)
    np.testing.assert_allclose(out["confidence_fraction"].values, [2.8 / 3.0, 0.0092 / 0.01, 10.0 / 45.0])
    assert out.attrs["undetermined"] == "ALPHAV2 HBNC71"
    assert out.attrs["undetermined_warning"].startswith("the training data (BCF1) leave ALPHAV2, HBNC71 undetermined")
    assert "held-out predictions that depend on them are not constrained" in out.attrs["undetermined_warning"]
    determined = stage._add_undetermined(ds.assign(confidence_upper=("param", [1.0, 0.012, 61.0])))
    assert determined.attrs["undetermined"] == "" and "undetermined_warning" not in determined.attrs
