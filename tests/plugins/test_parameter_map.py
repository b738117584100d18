"""Grouped and log-scale design columns: the ``parameter_space`` stage records which UTCHEM names each column sets
and its scale, designs carry that map, and the forward stage simulates a row exactly as the simulator does when
called with the UTCHEM values written out by hand."""

import numpy as np
import pytest
import xarray as xr

import spflow
from spflow.core.stage import StageContext
from spflow.plugins.design.latin_hypercube import LatinHypercubeDesign
from spflow.plugins.design.parameter_map import ParameterMap
from spflow.plugins.design.parameter_space import ParameterSpace
from spflow.plugins.forward.parameters import PARAMETERS
from spflow.plugins.forward.simulate import simulate
from spflow.plugins.forward.stage import Forward

CTX = StageContext("test", verbose=False)
SPECS = {p.name: p for p in PARAMETERS}
RANGES = {"ALPHAV2": [0.0, 3.0],
          "n_low": {"names": ["E1WC", "E2WC", "E3WC"], "range": [1.5, 3.0]},
          "CRK": {"range": [0.02, 0.2], "scale": "log"}}


def _space():
    return ParameterSpace(names=list(RANGES), ranges=RANGES).run(CTX)


def test_space_records_names_scale_and_log_bounds():
    space = _space()
    assert space["param"].values.tolist() == ["ALPHAV2", "n_low", "CRK"]
    assert space["utchem_names"].values.tolist() == ["ALPHAV2", "E1WC E2WC E3WC", "CRK"]
    assert space["scale"].values.tolist() == ["linear", "linear", "log"]
    np.testing.assert_allclose(space["lower"].values, [0.0, 1.5, np.log10(0.02)], rtol=1e-15)
    np.testing.assert_allclose(space["upper"].values, [3.0, 3.0, np.log10(0.2)], rtol=1e-15)
    # UDUNITS form: the catalogue's "-" is "1"; CRK's darcy^(1/2)*(wt%)^(1/3) is 2.1403019e-07 m (a length)
    assert SPECS["ALPHAV2"].unit == "-" and SPECS["CRK"].unit == "darcy^(1/2)*(wt%)^(1/3)"
    assert space["unit"].values.tolist() == ["1", "1", "lg(re 1 2.1403019e-07 m)"]
    assert space["lower"].attrs == {"units_variable": "unit"}
    # the default of a log column is log10 of the forward model's default (0.068, inside the range)
    assert float(space["default"].sel(param="CRK")) == pytest.approx(np.log10(SPECS["CRK"].default), rel=1e-15)


def test_design_rows_become_the_utchem_values_written_out():
    design = LatinHypercubeDesign(samples=5, seed=3).run(CTX, _space())
    mapping = ParameterMap.of(design)
    for row in design["values"].values:
        expected = {"ALPHAV2": row[0], "E1WC": row[1], "E2WC": row[1], "E3WC": row[1], "CRK": 10.0 ** row[2]}
        got = mapping.forward_params(row)
        assert got.keys() == expected.keys()
        for name, value in expected.items():
            assert got[name] == pytest.approx(value, rel=1e-14), name
        np.testing.assert_allclose(mapping.columns(got), row, rtol=1e-13)
        assert 0.02 <= got["CRK"] <= 0.2
    # log-uniform in the value: the design's log10(CRK) is one point per stratum of [log10 0.02, log10 0.2]
    unit = (design["values"].sel(param="CRK").values - np.log10(0.02)) / (np.log10(0.2) - np.log10(0.02))
    assert sorted(np.floor(unit * 5).astype(int).tolist()) == [0, 1, 2, 3, 4]


def test_forward_stage_simulates_a_grouped_log_row_as_the_simulator_with_the_values_written_out():
    row = np.array([[1.1, 2.4, np.log10(0.045)]])
    design = ParameterMap.of(_space()).design(row)
    out = Forward(experiments=["BCF1"], cells=12, pv_step=0.1).run(CTX, design=design)
    params = {"ALPHAV2": 1.1, "E1WC": 2.4, "E2WC": 2.4, "E3WC": 2.4, "CRK": 0.045}
    reference = simulate("BCF1", params, cells=12, pv_step=0.1)
    for name in ("dp", "recovery"):
        got = out[name].isel(sample=0, experiment=0).dropna("pv").values
        np.testing.assert_allclose(got, reference[name].values, rtol=1e-12, err_msg=name)
    # and not as the oleic exponent alone: E1WC and E3WC matter
    oleic_only = simulate("BCF1", {"ALPHAV2": 1.1, "E2WC": 2.4, "CRK": 0.045}, cells=12, pv_step=0.1)
    assert np.max(np.abs(oleic_only["dp"].values - reference["dp"].values)) > 1.0  # Pa


def test_a_design_without_a_map_has_utchem_names_as_columns():
    design = xr.Dataset({"values": (("sample", "param"), [[0.05, 2.5]])}, coords={"param": ["CRK", "E2C"]})
    assert ParameterMap.of(design).forward_params(design["values"].values[0]) == {"CRK": 0.05, "E2C": 2.5}


@pytest.mark.parametrize("names, ranges, message", [
    (["n_high"], {}, "unknown forward-model parameter 'n_high'.*needs a table in 'ranges'"),
    (["n_high"], {"n_high": {"names": ["E1C", "NOPE"], "range": [1.5, 3.0]}}, "unknown forward-model parameter 'NOPE'"),
    (["n_high", "E2C"], {"n_high": {"names": ["E1C", "E2C"], "range": [1.5, 3.0]}},
     r"\['E2C'\] set by more than one column"),
    (["g"], {"g": {"names": ["E1C", "GAMHF"], "range": [1.5, 3.0]}}, "have different units"),
    (["CRK"], {"CRK": {"range": [0.0, 0.2], "scale": "log"}}, r"a log scale needs lower > 0"),
    (["CRK"], {"CRK": {"range": [0.01, 0.2], "scale": "ln"}}, r"'scale' must be one of \['linear', 'log'\]"),
    (["CRK"], {"CRK": [0.01, 0.2], "GAMHF": [50.0, 70.0]}, r"'ranges' has \['GAMHF'\], which are not in 'names'"),
    (["n_high"], {"n_high": {"names": ["E1C"], "range": [1.5, 9.0]}}, r"leaves the bounds of E1C \[1, 6\]"),
])
def test_bad_grouped_spaces_are_rejected_when_the_stage_is_built(names, ranges, message):
    with pytest.raises(spflow.ParameterError, match=message):
        ParameterSpace(names=names, ranges=ranges)


def test_posterior_draws_reach_the_slug_design_through_the_map():
    from spflow.plugins.calibration.posterior import posterior_dataset
    from spflow.plugins.slug_design.objectives import Realisations, SlugDesignProblem

    space = _space()
    theta = np.array([[[1.0, 2.2, np.log10(0.05)], [2.0, 1.8, np.log10(0.03)]]])  # (chain, draw, param)
    posterior = posterior_dataset(theta, np.ones((1, 2, 1)), np.zeros((1, 2)), np.zeros((1, 2)), np.ones(1),
                                  space=space, pairs=[("dp", "BCF1")], points=[10], units=["Pa"], attrs={})
    assert posterior["utchem_names"].values.tolist() == ["ALPHAV2", "E1WC E2WC E3WC", "CRK"]
    draws = Realisations(SlugDesignProblem(), theta[0], ParameterMap.of(posterior))
    got = draws.parameters(theta[0, 1])
    expected = {"ALPHAV2": 2.0, "E1WC": 1.8, "E2WC": 1.8, "E3WC": 1.8, "CRK": 0.03}
    assert got.keys() == expected.keys()
    assert all(got[k] == pytest.approx(v, rel=1e-14) for k, v in expected.items())
