"""The screening stages end to end on the forward model (3 parameters, cells = 30): run counts, dims, units,
finiteness, index consistency, an ignored parameter with zero indices, per-group vs joint designs, Morris, the
reduced space feeding ``lhs_design`` and the Fig. 3.2 plot of the result."""

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

from spflow.core.stage import StageContext  # noqa: E402
from spflow.plugins.design.latin_hypercube import LatinHypercubeDesign  # noqa: E402
from spflow.plugins.design.parameter_space import ParameterSpace  # noqa: E402
from spflow.plugins.design.schemas import SPACE  # noqa: E402
from spflow.plugins.screening.figure import plot_total_indices  # noqa: E402
from spflow.plugins.screening.morris_screening import MorrisScreening  # noqa: E402
from spflow.plugins.screening.selected_space import SelectedSpace  # noqa: E402
from spflow.plugins.screening.sobol_screening import SobolScreening  # noqa: E402

CTX = StageContext("screening", verbose=False)
NAMES = ["AD31", "HBNC70", "E2C"]
# surfactant adsorption off: the forward model multiplies AD31 by 0, so AD31 cannot change any output
COMMON = {"cells": 30, "effects": {"surfactant_adsorption": 0.0}, "seed": 3}


@pytest.fixture(scope="module")
def space():
    return ParameterSpace(names=NAMES, ranges={"AD31": [0.0, 2.0], "HBNC70": [0.02, 0.05], "E2C": [1.5, 3.0]}).run(CTX)


@pytest.fixture(scope="module")
def joint(space):
    stage = SobolScreening(samples=8, calc_second_order=True, mode="joint", threshold=0.05, **COMMON)
    out = stage.run(CTX, space=space)
    stage.output.validate(out, stage=stage.name, port="output")
    return out


def test_joint_run_count_dims_units_and_finiteness(joint):
    assert joint.attrs["runs"] == (2 * 3 + 2) * 8
    assert joint["ST"].dims == ("qoi", "param") and joint["S2"].dims == ("qoi", "param", "param_j")
    assert joint["qoi"].values.tolist() == ["recovery_final:BCF1", "dp_max:BCF1"]
    assert joint["qoi_units"].values.tolist() == ["1", "Pa"]
    assert joint["param"].values.tolist() == NAMES and set(joint["group"].values) == {"all"}
    for k in ("S1", "S1_conf", "ST", "ST_conf", "variance", "score"):
        assert np.isfinite(joint[k].values).all(), k
    assert all(joint[k].attrs["units"] == "1" for k in ("S1", "S1_conf", "ST", "ST_conf", "score"))
    assert (joint["variance"].values > 0).all()
    np.testing.assert_array_equal(joint["lower"].values, [0.0, 0.02, 1.5])


def test_ignored_parameter_has_zero_indices_and_is_not_selected(joint):
    ad31 = joint.sel(param="AD31")
    assert (ad31["S1"].values == 0).all() and (ad31["ST"].values == 0).all()
    # second-order indices combine several estimator terms: an inert parameter leaves round-off (~1e-16) there
    assert np.nansum(np.abs(joint["S2"].sel(param="AD31").values)) <= 1e-12
    assert np.nansum(np.abs(joint["S2"].sel(param_j="AD31").values)) <= 1e-12
    assert not bool(ad31["selected"])
    # the two active parameters carry the variance: their total indices add up to at least ~1
    active = joint[["ST", "ST_conf"]].sel(param=["HBNC70", "E2C"]).sum("param")
    assert ((active["ST"] + active["ST_conf"]).values > 0.9).all()


def test_total_index_not_below_first_order_beyond_the_intervals(joint):
    slack = joint["S1_conf"] + joint["ST_conf"]
    assert bool((joint["ST"] >= joint["S1"] - slack).all())
    score = joint["ST"].max("qoi")
    np.testing.assert_array_equal(joint["score"].values, score.values)
    np.testing.assert_array_equal(joint["selected"].values, score.values >= 0.05)


def test_per_group_designs_hold_the_other_group_at_defaults(space):
    groups = {"surfactant": ["AD31", "HBNC70"], "relperm": ["E2C"]}
    out = SobolScreening(samples=8, groups=groups, qois=["recovery_final", "dp_max", "recovery"], **COMMON).run(
        CTX, space=space)
    assert out.attrs["runs"] == 8 * (2 + 2) + 8 * (1 + 2)
    assert out["group"].values.tolist() == ["surfactant", "surfactant", "relperm"]
    # E2C alone in its design: all of that design's variance is E2C's, so S1 and ST are ~1 (estimator noise, N = 8)
    e2c = out.sel(param="E2C", qoi=["recovery_final:BCF1", "dp_max:BCF1"])
    assert (e2c["ST"].values > 0.5).all() and (e2c["S1"].values > 0.5).all()
    # per-time-step indices: recovery at 0 PV does not vary -> 0; AD31 is inert at every step
    series = out.isel(qoi=np.flatnonzero(out["qoi_variable"].values == "recovery"))
    assert series["qoi_pv"].values[0] == 0.0 and (series["ST"].values[0] == 0).all()
    assert (series["ST"].sel(param="AD31").values == 0).all()
    assert (series["ST"].sel(param="HBNC70").values[-1] > 0.5)
    # variance differs per design: the surfactant group's QoI variance is that of HBNC70 alone
    variance = out["variance"].sel(qoi="dp_max:BCF1")
    assert float(variance.sel(param="AD31")) == float(variance.sel(param="HBNC70"))
    assert float(variance.sel(param="AD31")) != float(variance.sel(param="E2C"))


def test_morris_stage_ranks_the_ignored_parameter_last(space):
    stage = MorrisScreening(trajectories=4, threshold=0.05, **COMMON)
    out = stage.run(CTX, space=space)
    stage.output.validate(out, stage=stage.name, port="output")
    assert out.attrs["runs"] == 4 * (3 + 1)
    assert (out["mu_star"].sel(param="AD31").values == 0).all()
    assert float(out["score"].sel(param="AD31")) == 0.0 and float(out["score"].max()) == 1.0
    assert not out["selected"].values[0] and out["selected"].values[1:].any()


def test_selected_space_feeds_lhs_design(joint):
    reduced = SelectedSpace().run(CTX, screening=joint)
    SPACE.validate(reduced, stage="selected_space", port="output")
    kept = joint["param"].values[joint["selected"].values].tolist()
    assert reduced["param"].values.tolist() == kept and "AD31" not in kept
    design = LatinHypercubeDesign(samples=16, seed=1).run(CTX, space=reduced)
    lo, hi = reduced["lower"].values, reduced["upper"].values
    assert design["values"].shape == (16, len(kept))
    assert ((design["values"].values >= lo) & (design["values"].values <= hi)).all()


def test_figure_bars_are_the_total_indices(joint):
    fig = plot_total_indices(joint)
    ax = fig.axes[0]
    heights = np.array([p.get_height() for p in ax.patches]).reshape(2, 3)  # one bar series per QoI
    np.testing.assert_allclose(heights, joint["ST"].values)
    labels = [t.get_text() for t in ax.get_xticklabels()]
    assert labels[0] == "$ad_{31}$" and all(lab.endswith("*") == s for lab, s in zip(labels, joint["selected"].values))
