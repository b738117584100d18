"""load_coreflood on CSV (valid, partial, malformed), netCDF and TOML schedule files; every malformed file must
raise the documented ValueError naming the file, the line and the column."""

import json
import warnings

import numpy as np
import pytest

from spflow.io import load_coreflood, read_schedule_file
from spflow.io.format import schedule_json
from spflow.synthetic import NoiseModel, make_coreflood

PSI = 6894.757293168361  # Pa per psi (NIST)


def _write(tmp_path, text, name="flood.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


GOOD = """# experiment: lab7
# pore_volume_ml: 70.0
# ooip_ml: 56.0
# units: dp=kPa, recovery=%
# noise_pressure_relative: 0.03
pv,dp,oil_cut,recovery,c_polymer_out
0.02,7.5,,,
0.05,7.4,1.0,6.25,0
0.06,7.3,,,
0.10,7.2,0.5,9.375,120
"""


def test_csv_with_header_units_loads_into_the_format(tmp_path):
    ds = load_coreflood(_write(tmp_path, GOOD), schedule="BCF1")
    np.testing.assert_array_equal(ds["pv"].values, [0.02, 0.05, 0.06, 0.10])
    np.testing.assert_allclose(ds["dp"].values, [7500.0, 7400.0, 7300.0, 7200.0])
    np.testing.assert_array_equal(ds["pv_tube_end"].values, [0.05, 0.10])
    np.testing.assert_allclose(ds["pv_tube_start"].values, [0.0, 0.05])
    np.testing.assert_allclose(ds["pv_tube"].values, [0.025, 0.075])
    np.testing.assert_allclose(ds["recovery"].values, [0.0625, 0.09375])
    assert ds["dp"].attrs["units"] == "Pa" and ds["recovery"].attrs["units"] == "1"
    assert ds.attrs["experiment"] == "lab7" and ds.attrs["noise_pressure_relative"] == 0.03
    assert json.loads(ds.attrs["schedule"]) == json.loads(schedule_json("BCF1"))
    assert ds.attrs["missing"] == ""


def test_column_mapping_and_units_arguments_override_the_header(tmp_path):
    text = "Inj PV,dP (psi),Oil (ml),Operator\n0.05,1.0,3.5,ab\n0.10,1.1,0.7,ab\n"
    path = _write(tmp_path, "# pore_volume_ml: 70\n# ooip_ml: 56\n" + text)
    ds = load_coreflood(path, columns={"Inj PV": "pv", "dP (psi)": "dp", "Oil (ml)": "oil_volume",
                                       "Operator": None}, units={"dp": "psi"})
    np.testing.assert_allclose(ds["dp"].values, [PSI, 1.1 * PSI])
    np.testing.assert_allclose(ds["oil_cut"].values, [3.5 / 3.5, 0.7 / 3.5])  # oil / (0.05 PV x 70 ml)
    np.testing.assert_allclose(ds["recovery"].values, [3.5 / 56, 4.2 / 56])


def test_partial_data_only_pressure_is_carried_as_missing_qois(tmp_path):
    ds = load_coreflood(_write(tmp_path, "pv,dp\n0.1,100\n0.2,120\n"))
    assert list(ds.data_vars) == ["dp"] and "pv_tube" not in ds.dims
    assert ds.attrs["measured"] == "dp" and ds.attrs["missing"] == "oil_cut recovery"


def test_synthetic_twin_written_as_lab_csv_loads_back_identically(tmp_path):
    twin = make_coreflood("BCF1", cells=40, pv_step=0.01, noise=NoiseModel(tube_pv=0.1, pressure_interval_pv=0.05))
    rows = {}
    for pv, dp in zip(twin["pv"].values, twin["dp"].values):
        rows.setdefault(float(pv), {})["dp"] = dp
    tube_cols = ["oil_cut", "recovery", "c_polymer_out", "salinity_out"]
    for i, end in enumerate(twin["pv_tube_end"].values):
        rows.setdefault(float(end), {}).update({c: twin[c].values[i] for c in tube_cols})
    lines = ["pv,dp," + ",".join(tube_cols)]
    for pv in sorted(rows):
        cells = [rows[pv].get(c) for c in ["dp"] + tube_cols]
        lines.append(",".join([repr(pv)] + ["" if v is None else repr(float(v)) for v in cells]))
    ds = load_coreflood(_write(tmp_path, "\n".join(lines) + "\n"))
    for name in ["dp"] + tube_cols:
        np.testing.assert_array_equal(ds[name].values, twin[name].values)
        assert ds[name].dims == twin[name].dims and ds[name].attrs["units"] == twin[name].attrs["units"]
    np.testing.assert_allclose(ds["pv_tube_start"].values, twin["pv_tube_start"].values, atol=1e-12)


def test_tube_rows_that_look_like_midpoints_are_named_not_changed(tmp_path):
    """Tubes of 0.05 PV written at their midpoints (0.025, 0.075, ...) read as ends make a first tube of half the
    size: the loader keeps the documented reading and says so (warning and attr); true tube ends say nothing."""
    mids = "pv,oil_cut\n" + "".join(f"{0.025 + 0.05 * k:.3f},0.5\n" for k in range(6))
    with pytest.warns(UserWarning, match=r"line 2: the first tube \(0, 0.025\] PV is half the size of the other 5"):
        ds = load_coreflood(_write(tmp_path, mids))
    assert "tube midpoints" in ds.attrs["tube_rows_note"]
    np.testing.assert_allclose(ds["pv_tube_end"].values, 0.025 + 0.05 * np.arange(6))  # read as documented
    ends = "pv,oil_cut\n" + "".join(f"{0.05 * (k + 1):.3f},0.5\n" for k in range(6))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert "tube_rows_note" not in load_coreflood(_write(tmp_path, ends, "ends.csv")).attrs


@pytest.mark.parametrize("text, line, column, message", [
    ("pv,dp\n0.1,100\n0.3,110\n0.2,120\n", 4, "pv", "non-monotonic PV"),
    ("pv,oil_volume\n0.1,1.0\n0.2,-0.5\n", 3, "oil_volume", "negative volume"),
    ("pv,oil_cut\n0.1,0.5\n0.2,1.2\n", 3, "oil_cut", "outside the allowed range [0, 1]"),
    ("# units: oil_cut=%\npv,oil_cut\n0.1,50\n0.2,-3\n", 4, "oil_cut", "outside the allowed range [0, 1]"),
    ("pv,dp\n0.1,100\n0.2,NaN\n", 3, "dp", "NaN"),
    ("pv,dp\n0.1,100\n0.2,1O0\n", 3, "dp", "is not a number"),
    ("pv,dp\n0.1,100\n0.2,110,5\n", 3, None, "3 fields, expected 2"),
    ("pv,dp\n0.1,100\n,110\n", 3, "pv", "missing PV"),
    ("pv,oil_cut,recovery\n0.1,0.5,0.1\n0.2,0.4,\n", 3, "recovery", "missing value in a tube row"),
])
def test_malformed_rows_name_file_line_and_column(tmp_path, text, line, column, message):
    path = _write(tmp_path, text)
    with pytest.raises(ValueError) as err:
        load_coreflood(path)
    text = str(err.value)
    assert str(path) in text and f"line {line}" in text and message in text
    if column:
        assert f"column {column!r}" in text


@pytest.mark.parametrize("text, kwargs, message", [
    ("pv,dp\n0.1,100\n", {"units": {"dp": "atm"}}, "unknown unit 'atm' for column 'dp'; allowed units: Pa, kPa"),
    ("# units: recovery=percent\npv,recovery\n0.1,1\n", {}, "unknown unit 'percent' for column 'recovery'"),
    ("dp,oil_cut\n100,0.5\n", {}, "missing column 'pv'"),
    ("pv\n0.1\n", {}, "missing columns: no measured quantity"),
    ("pv,pressure\n0.1,100\n", {}, "unknown column 'pressure'"),
    ("pv,dp\n0.1,100\n", {"columns": {"DP": "dp"}}, "maps column 'DP', which is not in the file"),
    ("pv,dp\n0.1,100\n", {"units": {"pressure": "Pa"}}, "names unknown column 'pressure'"),
    ("# pore_volume_ml: -70\npv,dp\n0.1,100\n", {}, "line 1, header key 'pore_volume_ml'"),
])
def test_malformed_files_raise_documented_errors(tmp_path, text, kwargs, message):
    path = _write(tmp_path, text)
    with pytest.raises(ValueError) as err:
        load_coreflood(path, **kwargs)
    assert str(path) in str(err.value) and message in str(err.value)


def test_unknown_names_and_file_types_are_rejected(tmp_path):
    with pytest.raises(ValueError, match="not a bundled dataset name: BCF1, BCF2, BCF3"):
        load_coreflood("BCF4")
    with pytest.raises(ValueError, match=r"unknown file type '\.xlsx'"):
        load_coreflood(_write(tmp_path, "x", name="flood.xlsx"))


def test_netcdf_in_the_format_round_trips_and_bad_units_are_named(tmp_path):
    twin = make_coreflood("BCF1", cells=40, pv_step=0.01, seed=3)
    good = tmp_path / "twin.nc"
    twin.to_netcdf(good)
    loaded = load_coreflood(good)
    for name in twin.variables:
        np.testing.assert_array_equal(loaded[name].values, twin[name].values)
    bad = twin.copy()
    bad["dp"].attrs["units"] = "psi"
    bad.to_netcdf(tmp_path / "bad.nc")
    with pytest.raises(ValueError, match=r"bad\.nc.*variable 'dp' has units 'psi'; expected 'Pa'"):
        load_coreflood(tmp_path / "bad.nc")
    cut = twin.copy()
    cut["oil_cut"].values[5] = 1.5
    cut.to_netcdf(tmp_path / "cut.nc")
    with pytest.raises(ValueError, match=r"variable 'oil_cut' index 5 = 1.5 is outside \[0, 1\]"):
        load_coreflood(tmp_path / "cut.nc")


def test_schedule_file_is_read_and_validated(tmp_path):
    toml = _write(tmp_path, 'name = "mine"\n[[slugs]]\nname = "IWF"\npv = 1.5\nsalinity_ppm = 9400\n'
                            '[[slugs]]\npv = 0.5\nsalinity_ppm = 9400\nsurfactant_ppm = 6780\npolymer_ppm = 3300\n',
                  name="mine.toml")
    sched = read_schedule_file(toml)
    assert sched.name == "mine" and [s.pv for s in sched.slugs] == [1.5, 0.5] and sched.slugs[1].polymer_ppm == 3300
    csv = _write(tmp_path, "# schedule: mine.toml\npv,dp\n0.1,100\n")
    assert json.loads(load_coreflood(csv).attrs["schedule"])["slugs"][1]["surfactant_ppm"] == 6780
    bad = _write(tmp_path, '[[slugs]]\npv = -1\nsalinity_ppm = 9400\n', name="bad.toml")
    with pytest.raises(ValueError, match=r"bad\.toml.*slug 0.*'pv'.*allowed \(0, inf\)"):
        read_schedule_file(bad)
    with pytest.raises(ValueError, match="missing.toml.*no such file"):
        load_coreflood(csv, schedule="missing.toml")
