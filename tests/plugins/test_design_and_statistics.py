"""Parameter spaces, Latin hypercube designs and ensemble quantiles, checked against their defining properties."""

import numpy as np
import pytest
import xarray as xr

import spflow
from spflow.plugins.forward.parameters import PARAMETERS

DEFAULTS = {p.name: p for p in PARAMETERS}


def _space(cache, **params):
    p = spflow.Pipeline("space").add("space", "parameter_space", params=params)
    return spflow.run(p, cache=cache)["space"]


def test_relative_space_is_plus_minus_20_percent_around_defaults(tmp_path):
    space = _space(tmp_path, names=["AD31", "CRK"], relative=0.2)
    for name in ["AD31", "CRK"]:
        d = DEFAULTS[name].default
        assert float(space["lower"].sel(param=name)) == pytest.approx(0.8 * d, rel=1e-12)
        assert float(space["upper"].sel(param=name)) == pytest.approx(1.2 * d, rel=1e-12)
    # units in UDUNITS form (catalogue "-" is "1"; CRK's unit has none and stays as written)
    assert [DEFAULTS[n].unit for n in ("AD31", "CRK")] == ["-", "darcy^(1/2)*(wt%)^(1/3)"]
    assert space["unit"].values.tolist() == ["1", "2.1403019e-07 m"]


def test_explicit_ranges_and_bad_ranges(tmp_path):
    space = _space(tmp_path, names=["HBNC70"], ranges={"HBNC70": [0.02, 0.05]})
    assert space["lower"].values.tolist() == [0.02] and space["upper"].values.tolist() == [0.05]
    with pytest.raises(spflow.ParameterError,
                       match="'ranges' 'HBNC70': range \\[0.05, 0.02\\] must have lower < upper"):
        _space(tmp_path, names=["HBNC70"], ranges={"HBNC70": [0.05, 0.02]})
    with pytest.raises(spflow.ParameterError, match="unknown forward-model parameter 'NOPE'"):
        _space(tmp_path, names=["NOPE"])


def test_latin_hypercube_has_one_point_per_stratum(tmp_path):
    p = spflow.Pipeline("lhs")
    p.add("space", "parameter_space", params={"names": ["AD31", "GAMHF", "CRK"],
                                               "ranges": {"AD31": [0.0, 2.0], "GAMHF": [55.0, 100.0]}})
    p.add("design", "lhs_design", inputs={"space": "space"}, params={"samples": 40, "seed": 7})
    result = spflow.run(p, cache=tmp_path)
    design, space = result["design"], result["space"]
    assert design["values"].dims == ("sample", "param") and design.sizes["sample"] == 40
    unit = (design["values"] - space["lower"]) / (space["upper"] - space["lower"])
    for name in ["AD31", "GAMHF", "CRK"]:
        strata = np.floor(unit.sel(param=name).values * 40).astype(int)
        assert sorted(strata.tolist()) == list(range(40))  # exactly one point in each of the 40 strata


def test_quantiles_match_numpy(tmp_path):
    rng = np.random.default_rng(3)
    values = rng.normal(size=(50, 2, 7))
    ens = xr.Dataset(
        {"dp": (("sample", "experiment", "pv"), values, {"units": "Pa"}),
         "total_pv": ("experiment", [1.0, 2.0], {"units": "1"})},
        coords={"sample": np.arange(50), "experiment": ["A", "B"], "pv": np.linspace(0, 0.6, 7)},
    )
    p = spflow.Pipeline("q").add_data("ens", ens).add("q", "quantiles", inputs={"ensemble": "ens"},
                                                       params={"levels": [0.1, 0.9]})
    q = spflow.run(p, cache=tmp_path)["q"]
    np.testing.assert_allclose(q["dp"].sel(quantile=0.1).values, np.quantile(values, 0.1, axis=0), rtol=1e-12)
    np.testing.assert_allclose(q["dp_mean"].values, values.mean(axis=0), rtol=1e-12)
    assert q["dp"].attrs["units"] == "Pa" and q["total_pv"].values.tolist() == [1.0, 2.0]
    with pytest.raises(spflow.ParameterError, match="outside the allowed range \\[0.0, 1.0\\]"):
        spflow.run(spflow.Pipeline("q2").add_data("ens", ens).add("q", "quantiles", inputs={"ensemble": "ens"},
                                                                   params={"levels": [1.5]}), cache=tmp_path)


def test_quantiles_skip_failure_reasons_and_failed_rows():
    """A forward ensemble with a failed sample (NaN row, a ``failure`` reason): the quantiles are those of the
    finished samples (numpy's nanquantile here) and the failure count is recorded."""
    from spflow.core.stage import StageContext
    from spflow.plugins.statistics.quantiles import Quantiles

    dp = np.array([[1.0, 2.0], [3.0, 4.0], [np.nan, np.nan], [5.0, 8.0]])
    ensemble = xr.Dataset({"dp": (("sample", "pv"), dp, {"units": "Pa"}),
                           "failure": ("sample", np.array(["", "", "BCF1: step budget", ""], dtype=object))})
    out = Quantiles(levels=[0.5]).run(StageContext("q", n_jobs=1, verbose=False), ensemble=ensemble)
    assert "failure" not in out and out.attrs["failed_samples"] == 1
    np.testing.assert_allclose(out["dp"].sel(quantile=0.5).values, np.nanquantile(dp, 0.5, axis=0))
    np.testing.assert_allclose(out["dp_mean"].values, np.nanmean(dp, axis=0))
