"""Units and long names of what spflow writes (docs/architecture.md, "Units and CF metadata"), judged by a units
library: cf-units, which bundles UDUNITS-2 (``cf_check``).

* Every variable declared by a built-in stage's schemas has a ``long_name``, and a ``units`` UDUNITS parses (or units
  per element). The declarations not there yet are listed in ``NOT_YET`` with the reason; the list may only shrink:
  a new offender fails, and so does a listed one that has been fixed (take it off the list).
* Every built-in stage, run on small inputs (``builtin_stage_cases``), writes (what the executor stores: annotated,
  units in UDUNITS form, :func:`note_units`) only units UDUNITS parses: no exceptions.
* A small real run (the chapter-4 pipeline, tiny budgets) through the executor and cache: a stored result that claims
  ``Conventions = "CF-1.10"`` passes the strict check (no units per element); the posterior passes the check with
  units per element, CRK's included; the InferenceData file the report writes is the one ``from_run`` builds, and
  every group claims CF and passes the strict check.
"""

import math
import re

import numpy as np
import pytest
import xarray as xr
from builtin_stage_cases import CASES, Small
from cf_check import dataset_problems, unit_problem

from spflow.core.cf_metadata import CONVENTIONS, CRK_UNIT, claims_cf, note_units, udunits
from spflow.core.plugins import get_registry

#: (schema doc, variable) -> why its declared units are not UDUNITS yet.
NOT_YET = {
    ("design points", "values"):
        "what the stages taking a design accept: a design a user gives (Pipeline.add_data, load_netcdf) may carry no "
        "units; the stages drawing one write 'design points with the units of their columns'",
    **{("a fitted surrogate (see attrs['surrogate'] for its kind)", v):
       "what the stages taking a surrogate accept: a third-party surrogate stage's output may carry no units per "
       "parameter; the built-in surrogate stages write the stored form with them" for v in ("lower", "upper")},
}


def _declared():
    """(schema doc, variable) -> (where first declared, Variable), over every built-in stage's input and output."""
    out = {}
    for name, cls in sorted(get_registry().stages.items()):
        for port, schema in [("output", cls.output), *cls.inputs.items()]:
            for var, spec in (schema.variables.items() if schema is not None else ()):
                out.setdefault((schema.doc, var), (f"{name}.{port}", spec))
    return out


def _units_problem(spec) -> str | None:
    if not set(spec.kind) & set("fiu") or spec.units_variable is not None:
        return None
    return unit_problem(spec.units) if spec.units else f"units {spec.units!r} (not declared)"


def test_every_declared_variable_has_a_long_name():
    missing = [f"{where} {key[1]}" for key, (where, spec) in _declared().items() if not spec.long_name.strip()]
    assert missing == []


def test_declared_units_parse_except_the_listed_ones():
    problems = {key: _units_problem(spec) for key, (_, spec) in _declared().items()}
    problems = {key: why for key, why in problems.items() if why}
    new = {f"{_declared()[key][0]} {key[1]}": why for key, why in problems.items() if key not in NOT_YET}
    fixed = [key for key in NOT_YET if key not in problems]
    assert new == {}
    assert fixed == [], "declared units now parse: take these off NOT_YET"


def test_the_checker_and_the_claim_agree_on_hand_made_datasets():
    theta = xr.Dataset({"theta": ("param", [1.0, 2.0], {"long_name": "x", "units_variable": "unit"}),
                        "unit": ("param", ["cpoise", "m"], {"long_name": "u"})},
                       coords={"param": ("param", ["a", "b"], {"long_name": "p"})})
    assert dataset_problems(theta) == [] and not claims_cf(theta)
    assert dataset_problems(theta, per_element=False) == ["theta: no units"]
    pv = xr.Dataset({"pv": ("pv", [0.1], {"units": "PV", "long_name": "injected pore volumes"})})
    assert dataset_problems(pv) == ["pv: units 'PV' reads as petavolt in UDUNITS"] and not claims_cf(pv)
    fine = xr.Dataset({"dp": ("pv", [1.0], {"units": "kPa", "long_name": "pressure drop"}),
                       "pv": ("pv", [0.1], {"units": "1", "long_name": "injected pore volumes"})})
    assert dataset_problems(fine, per_element=False) == [] and claims_cf(fine)
    assert not claims_cf(fine.assign(q=("pv", [2.0], {"units": "1"})))  # no long_name


@pytest.mark.parametrize("notation, meaning", [("-", "1"), ("cP", "mPa s"), ("lg(re 1 cP)", "lg(re 1 mPa s)"),
                                               ("wt%", "percent"), ("PV", "1"), ("nat", "1"), ("mD", "millidarcy"),
                                               ("(wt%)^-2", "percent^-2"), ("meq/ml", "mol/l"),
                                               ("ml/meq", "l/mol"), ("(1/s)/(meq/ml)", "l mol-1 s-1"),
                                               ("M$", "1000000"), ("$/bbl", "bbl-1"), ("iterations", "1")])
def test_catalogue_notation_becomes_the_udunits_unit_meant(notation, meaning):
    """Hand-written meanings: 1 meq/ml = 1 mmol (of unit charge)/ml = 1 mol/l; 1 M$ = 1e6 (US dollars)."""
    import cf_units

    written, meant = cf_units.Unit(udunits(notation)), cf_units.Unit(meaning)
    assert written.is_convertible(meant) and written.convert(1.0, meant) == pytest.approx(1.0, rel=1e-12)


def test_crk_unit_is_darcy_to_the_half_times_wt_percent_to_the_third():
    """darcy^(1/2) (wt%)^(1/3) (docs/forward_model.md, "Units"), computed here from the SI value of a darcy
    (1 cP cm2 / (s atm) = 1e-3 Pa s x 1e-4 m2 / (1 s x 101325 Pa)) and 0.01^(1/3); the old label maps to it too."""
    import cf_units

    darcy_m2 = 1e-3 * 1e-4 / 101325.0
    metres = math.sqrt(darcy_m2) * 0.01 ** (1.0 / 3.0)
    unit = cf_units.Unit(udunits("darcy^(1/2)*(wt%)^(1/3)"))
    assert unit.is_convertible("m") and unit.convert(1.0, "m") == pytest.approx(metres, rel=1e-6)
    assert udunits("darcy^0.5*(wt%)^-1/3") == CRK_UNIT
    log = udunits("lg(re 1 darcy^(1/2)*(wt%)^(1/3))")
    assert log == f"lg(re 1 {CRK_UNIT})" and unit_problem(log) is None


def test_gammac_unit_is_a_number():
    """day darcy^(1/2) / (ft s) = 86400 s x sqrt(darcy) / (0.3048 m x 1 s), a number computed here."""
    import cf_units

    darcy_m2 = 1e-3 * 1e-4 / 101325.0
    number = 86400.0 * math.sqrt(darcy_m2) / 0.3048
    assert cf_units.Unit(udunits("day*darcy^(1/2)/(ft*s)")).convert(1.0, "1") == pytest.approx(number, rel=1e-6)


def test_every_catalogue_unit_has_its_udunits_form():
    """It parses, and no fractional power is left (UDUNITS reads "darcy^0.5" as darcy^0 x 5 and accepts it)."""
    from spflow.plugins.forward.parameters import PARAMETERS

    assert {p.name: p.unit for p in PARAMETERS if unit_problem(udunits(p.unit))} == {}
    fractional = re.compile(r"\^\s*-?\d+\.\d|\^\s*\(\s*-?\d+\s*/")
    assert {p.name: udunits(p.unit) for p in PARAMETERS if fractional.search(udunits(p.unit))} == {}


def test_what_udunits_cannot_say_is_in_an_attribute_and_the_long_name():
    ds = xr.Dataset({"cse": ("point", [0.1], {"units": "meq/ml", "long_name": "effective salinity"}),
                     "npv": ("draw", [1.5], {"units": "M$", "long_name": "NPV"}),
                     "dp": ("draw", [1.0], {"units": "kPa", "long_name": "dp"}),
                     "theta": ("param", [0.1, 2.0], {"units_variable": "unit", "long_name": "theta"}),
                     "unit": ("param", ["meq/ml", "cP"], {"long_name": "units"})})
    out = note_units(ds)
    assert out["cse"].attrs == {"units": "mmol/ml", "long_name": "effective salinity (meq/ml)",
                                "equivalents": "mmol of unit charge (meq)"}
    assert out["npv"].attrs == {"units": "1e6", "long_name": "NPV (M$: million US dollars)", "currency": "USD"}
    assert out["dp"].attrs == ds["dp"].attrs
    assert out["unit"].values.tolist() == ["mmol/ml", "cpoise"] and out["unit"].attrs["equivalents"]
    assert ds["unit"].values.tolist() == ["meq/ml", "cP"] and ds["cse"].attrs["units"] == "meq/ml"  # a copy
    assert dataset_problems(out) == [] and claims_cf(out.drop_vars(["theta", "unit"]))


@pytest.fixture(scope="module")
def small():
    return Small()


@pytest.mark.parametrize("name", sorted(CASES))
def test_every_unit_a_builtin_stage_writes_parses(name, small):
    from spflow.core.plugins import get_registry

    params, inputs, _ = CASES[name](small)
    stage = get_registry().stage(name)(**params)
    out = stage.run(small.ctx, **inputs)
    written = note_units(stage.output.annotate(out) if stage.output is not None else out)  # as the executor does
    assert dataset_problems(written, long_names=False) == []


def test_a_small_real_run_writes_what_it_claims(tmp_path):
    import spflow
    from spflow.pipelines import bayesian_calibration
    from spflow.plugins.calibration.diagnostics import arviz
    from spflow.plugins.calibration.inference_data import from_run

    pipe = bayesian_calibration.pipeline(samples=12, cells=20, degree_max=1, mcmc_samples=1_200, burn=400, thin=2,
                                         chains=2, draws=8, prior_draws=4)
    result = spflow.run(pipe, cache=tmp_path / "cache", verbose=False)
    claimed = []
    for node in result:
        ds = result[node]
        if ds.attrs.get("Conventions") == CONVENTIONS:
            claimed.append(node)
            assert dataset_problems(ds, per_element=False) == [], node
    # results with neither units per element nor CRK's unit claim CF (and passed the strict check above)
    assert {"observations", "responses", "prior_responses", "prior_bands"} <= set(claimed)
    posterior = result["posterior"]
    assert "posterior" not in claimed  # units per element: no CF claim
    # every unit of the posterior parses, CRK's included
    units = dict(zip(posterior["param"].values.tolist(), posterior["unit"].values.tolist()))
    assert units["CRK"] == CRK_UNIT and dataset_problems(posterior) == []
    # the report (what `spflow run bayesian_calibration` writes) leaves the same InferenceData as posterior.nc
    lines = bayesian_calibration.report(result, tmp_path)
    assert "posterior.nc (ArviZ InferenceData" in lines[0] and "every 1-th draw" in lines[0]
    idata = from_run(result)
    written = arviz().from_netcdf(tmp_path / "posterior.nc")
    assert sorted(written.groups()) == sorted(idata.groups())
    np.testing.assert_array_equal(written.log_likelihood["y"].values, idata.log_likelihood["y"].values)
    for group in idata.groups():
        assert dataset_problems(idata[group], per_element=False) == [], group
        assert idata[group].attrs["Conventions"] == CONVENTIONS, group
    assert np.isfinite(idata.log_likelihood["y"].values).all()


def test_the_schema_accepts_units_per_element_only_in_the_documented_form():
    from spflow.core.errors import SchemaError
    from spflow.core.schema import DatasetSchema, Variable

    schema = DatasetSchema(variables={"x": Variable(("p",), units_variable="u", long_name="x")})
    good = xr.Dataset({"x": ("p", [1.0, 2.0], {"units_variable": "u"}), "u": ("p", ["m", "s"])})
    schema.validate(good, stage="t", port="out")
    for bad, why in ((good.assign(x=("p", [1.0, 2.0])), "expected attrs\\['units_variable'\\] = 'u'"),
                     (good.assign(x=("p", [1.0, 2.0], {"units_variable": "u", "units": "m"})), "found 'm'"),
                     (good.drop_vars("u"), "found None\\)"),
                     (good.assign(u=("q", ["m", "s"])), "along some of its dims")):
        with pytest.raises(SchemaError, match=why):
            schema.validate(bad, stage="t", port="out")
    assert schema.annotate(good.assign(x=("p", [1.0, 2.0])))["x"].attrs == {"long_name": "x", "units_variable": "u"}


def test_units_per_pair_of_parameters_in_a_two_dimensional_units_variable():
    from spflow.core.cf_metadata import has_units_per_element
    from spflow.core.errors import SchemaError
    from spflow.core.schema import DatasetSchema, Variable

    schema = DatasetSchema(variables={"cov": Variable(("p", "q"), units_variable="cu", long_name="c")})
    cov = xr.Dataset({"cov": (("p", "q"), np.eye(2), {"units_variable": "cu", "long_name": "c"}),
                      "cu": (("p", "q"), [["(Pa)^2", "Pa s"], ["Pa s", "s^2"]], {"long_name": "u"})},
                     coords={"p": ("p", ["a", "b"], {"long_name": "p"}), "q": ("q", ["a", "b"], {"long_name": "q"})})
    schema.validate(cov, stage="t", port="out")
    assert has_units_per_element(cov, "cov") and dataset_problems(cov) == []
    typo = cov.assign(cu=(("p", "q"), [["(Pa)^2", "Pa s"], ["Pa s", "PV"]], {"long_name": "u"}))
    assert dataset_problems(typo) == ["cov: entry of cu: units 'PV' reads as petavolt in UDUNITS"]
    elsewhere = cov.assign(cu=(("p", "r"), [["m", "s"], ["m", "s"]]))  # a dim the covariance does not have
    assert not has_units_per_element(elsewhere, "cov")
    with pytest.raises(SchemaError, match="along some of its dims"):
        schema.validate(elsewhere, stage="t", port="out")


@pytest.mark.parametrize("a, b, meaning", [("cpoise", "1/percent", "mPa s/percent"), ("1", "Pa", "Pa"),
                                           ("Pa", "1", "Pa"), ("1/s", "1/s", "s-2"), ("1", "1", "1"),
                                           ("m/s", "m", "m2 s-1")])
def test_product_of_two_units_is_the_udunits_product(a, b, meaning):
    import cf_units

    from spflow.core.cf_metadata import product_unit, squared_unit

    assert cf_units.Unit(product_unit(a, b)) == cf_units.Unit(meaning)
    assert cf_units.Unit(squared_unit(a)) == cf_units.Unit(a) ** 2
