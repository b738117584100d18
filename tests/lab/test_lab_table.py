"""Lab-table reader: unit conversion, round trip, and located errors for malformed files."""

import numpy as np
import pytest
import xarray as xr

from spflow.plugins.lab.lab_table import LabDataError, convert, lab_meta, read_lab_table, write_lab_table

COLUMNS = {"c_polymer": ("wt%", "ppm"), "viscosity": ("cP", "mPa.s", "Pa.s"), "ift": ("mN/m", "dyn/cm")}

GOOD = """# kind: polymer_rheology
# experiment: sweep 1
# units: c_polymer=ppm, viscosity=Pa.s, ift=dyne/cm, note=1
# temperature: 25 degC
# length: 6 in
c_polymer,viscosity,ift,note
1000,0.0123,30,1
2500,0.050,20,2

# a comment between rows
5000,0.200,10,3
"""


def _write(tmp_path, text, name="t.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_reads_and_converts_to_canonical_units(tmp_path):
    ds = read_lab_table(_write(tmp_path, GOOD), "polymer_rheology", COLUMNS)
    assert ds.sizes == {"point": 3}
    np.testing.assert_allclose(ds["c_polymer"].values, [0.1, 0.25, 0.5])  # ppm -> wt%
    np.testing.assert_allclose(ds["viscosity"].values, [12.3, 50.0, 200.0])  # Pa.s -> cP
    np.testing.assert_allclose(ds["ift"].values, [30.0, 20.0, 10.0])  # dyne/cm == mN/m
    assert ds["viscosity"].attrs["units"] == "cP" and ds["c_polymer"].attrs["units"] == "wt%"
    assert "note" not in ds  # columns not asked for are ignored
    assert ds.attrs["kind"] == "polymer_rheology" and ds.attrs["experiment"] == "sweep 1"
    assert ds.attrs["meta_temperature"] == "25 degC"
    assert lab_meta(ds, "length", ("cm", "in")) == pytest.approx(15.24)


def test_round_trip_through_write(tmp_path):
    ds = xr.Dataset(
        {
            "c_polymer": ("point", np.array([0.05, 0.1, 0.2, 0.3])),
            "viscosity": ("point", np.array([3.0, 7.123456789, 20.0, np.nan])),
            "ift": ("point", np.array([1.0, 2.0, 3.0, 4.0])),
        },
        attrs={"experiment": "rt", "meta_salinity": "9400 ppm"},
    )
    for v, u in (("c_polymer", "wt%"), ("viscosity", "cP"), ("ift", "mN/m")):
        ds[v].attrs["units"] = u
    path = write_lab_table(ds, tmp_path / "rt.csv", "polymer_rheology")
    back = read_lab_table(path, "polymer_rheology", COLUMNS, allow_empty=("viscosity",))
    for v in ds.data_vars:
        np.testing.assert_allclose(back[v].values, ds[v].values, rtol=1e-9)
    assert back.attrs["meta_salinity"] == "9400 ppm" and back.attrs["experiment"] == "rt"
    assert lab_meta(back, "salinity", ("ppm", "wt%")) == 9400.0


def test_convert_units_independently():
    assert convert(1.0, "wt%", "ppm") == pytest.approx(1e4)
    assert convert(14.6959, "psi", "bar") == pytest.approx(1.01325, rel=1e-5)
    assert convert(1.0, "ml/min", "m3/s") == pytest.approx(1e-6 / 60)
    assert convert(1.0, "mS/cm", "uS/cm") == pytest.approx(1000.0)
    assert convert(0.01, "ft", "cm") == pytest.approx(0.3048)
    with pytest.raises(LabDataError, match="cannot convert"):
        convert(1.0, "cP", "ppm")


def _bad(text):
    return GOOD.replace(*text)


@pytest.mark.parametrize(
    "edit, kwargs, pattern",
    [
        (("# kind: polymer_rheology", "# kind: tracer"), {}, r"line 1: kind 'tracer' does not match"),
        (("# kind: polymer_rheology\n", ""), {}, r"line 1: missing '# kind"),
        (("c_polymer,viscosity,ift,note", "c_polymer,visc,ift,note"), {}, r"line 6 column 'viscosity': missing"),
        (("viscosity=Pa.s", "viscosity=poise"), {}, r"line 3 column 'viscosity': unknown unit 'poise'"),
        (("viscosity=Pa.s, ", ""), {}, r"line 3 column 'viscosity': no unit declared"),
        (("2500,0.050", "2500,abc"), {}, r"line 8 column 'viscosity': 'abc' is not a number"),
        (("2500,0.050", "2500,inf"), {}, r"line 8 column 'viscosity': 'inf' is not finite"),
        (("2500,0.050", "2500,nan"), {}, r"line 8 column 'viscosity': 'nan' is not finite"),
        (("2500,0.050", "2500,"), {}, r"line 8 column 'viscosity': empty cell"),
        (("5000,0.200,10,3\n", ""), {}, r"line 8: 2 data rows, at least 3"),
        (("5000,0.200,10,3", "5000,0.200,10"), {}, r"line 11: 3 cells, the header has 4"),
    ],
)
def test_malformed_files_name_file_line_and_column(tmp_path, edit, kwargs, pattern):
    path = _write(tmp_path, _bad(edit), "bad.csv")
    with pytest.raises(LabDataError, match=pattern) as err:
        read_lab_table(path, "polymer_rheology", COLUMNS, **kwargs)
    assert "bad.csv" in str(err.value)
    assert isinstance(err.value, ValueError)


def test_empty_cell_allowed_only_where_declared(tmp_path):
    path = _write(tmp_path, GOOD.replace("2500,0.050", "2500,"))
    ds = read_lab_table(path, "polymer_rheology", COLUMNS, allow_empty=("viscosity",))
    assert np.isnan(ds["viscosity"].values[1]) and np.isfinite(ds["viscosity"].values[[0, 2]]).all()


def test_missing_file_and_bad_column_spec(tmp_path):
    with pytest.raises(LabDataError, match="no such file"):
        read_lab_table(tmp_path / "none.csv", "polymer_rheology", COLUMNS)
    with pytest.raises(ValueError, match="different dimensions"):
        read_lab_table(_write(tmp_path, GOOD), "polymer_rheology", {"viscosity": ("cP", "ppm")})
    with pytest.raises(ValueError, match="not in UNITS"):
        read_lab_table(_write(tmp_path, GOOD), "polymer_rheology", {"viscosity": ("furlong",)})


def test_lab_meta_errors(tmp_path):
    ds = read_lab_table(_write(tmp_path, GOOD), "polymer_rheology", COLUMNS)
    with pytest.raises(LabDataError, match="'porosity': missing"):
        lab_meta(ds, "porosity")
    with pytest.raises(LabDataError, match="unit 'degC' not allowed"):
        lab_meta(ds, "temperature", ("K",))
    with pytest.raises(LabDataError, match="must be a bare number"):
        lab_meta(ds, "length")
