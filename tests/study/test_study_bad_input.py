"""Malformed studies and data files: each gets ONE clear StudyError naming the file, the field and the allowed
values, before any simulation; through the CLI (`spflow check`) it exits 2 with `spflow: error:` and no traceback."""

import json

import numpy as np
import pytest

import spflow.cli
import spflow.plugins.forward.kernel as kernel_module  # simulate() imports run_kernel from it when a run starts
from spflow.io.format import build_coreflood
from spflow.study import StudyError, load_study
from study_project import ROWS, STUDY, data_text, write_project

STUDY_FILE = "study.toml"
DATA_FILE = "core7.csv"


def _edit(old, new):
    def edit(text):
        assert old in text, old
        return text.replace(old, new)
    return edit


def _netcdf(attrs=None, recovery=None, name="core7.nc"):
    """A hand-made netCDF coreflood of the same shape as the CSV one (no simulation)."""
    def write(directory):
        pv = np.array([r[0] for r in ROWS])
        rec = np.array([r[3] for r in ROWS]) if recovery is None else np.asarray(recovery)
        ds = build_coreflood(experiment="core7", source="hand", pv=pv, dp=np.array([r[1] for r in ROWS]) * 6894.76,
                             tube_start=np.concatenate(([0.0], pv[:-1])), tube_end=pv,
                             tubes={"oil_cut": np.array([r[2] for r in ROWS]), "recovery": rec},
                             attrs=dict({"core_length_m": 0.3, "core_diameter_m": 0.0381, "porosity": 0.19,
                                         "swi": 0.28, "qinj_ml_min": 0.5}, **(attrs or {})))
        ds.to_netcdf(directory / name)
    return write


NC_STUDY = _edit('data = "core7.csv"', 'data = "core7.nc"')
_GOOD_SCHEDULE = json.dumps({"name": "s", "slugs": [{"name": "WF", "pv": 3.0, "salinity_ppm": 9400.0}]})

#: id -> (study edit or None, data edit (text -> text) / netCDF writer / None, file named, expected fragments)
CASES = {
    # --- the study file itself ---
    "unknown top-level key": (_edit("version = 1", "version = 1\nverison = 1"), None, STUDY_FILE,
                              ["unknown key(s) ['verison']", "allowed keys: ['version', 'parameters', 'effects'"]),
    "missing version": (_edit("version = 1\n", ""), None, STUDY_FILE, ["missing 'version'", "version = 1"]),
    "wrong version": (_edit("version = 1", "version = 2"), None, STUDY_FILE,
                      ["field 'version' = 2", "allowed versions: 1"]),
    "invalid TOML": (_edit("version = 1", "version = = 1"), None, STUDY_FILE, ["invalid TOML"]),
    "empty study": (lambda t: "", None, STUDY_FILE, ["empty file"]),
    "UTF-16 study": ("utf16", None, STUDY_FILE, ["UTF-16", "UTF-8"]),
    "binary study": ("binary", None, STUDY_FILE, ["not UTF-8 text"]),
    "unknown [parameters] key": (_edit("[parameters.fixed]", "[parameters.free]"), None, STUDY_FILE,
                                 ["[parameters]: unknown key(s) ['free']", "allowed keys: ['calibrated', 'fixed']"]),
    "no calibrated parameters": (_edit('HBNC71 = [0.01, 0.02]\nn_high = { names = ["E1C", "E2C", "E3C"], range = '
                                       '[1.5, 3.0] }\n', ""), None, STUDY_FILE,
                                 ["[parameters.calibrated] must list at least one", "name = [low, high]"]),
    "range outside bounds": (_edit("HBNC71 = [0.01, 0.02]", "HBNC71 = [0.0, 0.02]"), None, STUDY_FILE,
                             ["'HBNC71'", "leaves the bounds of HBNC71 [0.001, 0.5]"]),
    "unknown calibrated name": (_edit("HBNC71 = [0.01, 0.02]", "HBNC77 = [0.01, 0.02]"), None, STUDY_FILE,
                                ["unknown forward-model parameter 'HBNC77'", "spflow list params"]),
    "empty range": (_edit("HBNC71 = [0.01, 0.02]", "HBNC71 = [0.02, 0.01]"), None, STUDY_FILE,
                    ["'HBNC71'", "must have lower < upper"]),
    "core data as fixed": (_edit("VIS2 = 13.8", "VIS2 = 13.8\nLENGTH = 0.3"), None, STUDY_FILE,
                           ["[parameters.fixed] ['LENGTH']", "[experiment.core]"]),
    "fixed out of bounds": (_edit("VIS2 = 13.8", "VIS2 = -1.0"), None, STUDY_FILE,
                            ["VIS2", "allowed [0.1, 100000] cP"]),
    "unknown effect": (_edit("capillary_pressure = 0.0", "capilary_pressure = 0.0"), None, STUDY_FILE,
                       ["[effects]", "unknown effect 'capilary_pressure'", "known effects:"]),
    "effect out of range": (_edit("capillary_pressure = 0.0", "capillary_pressure = 50.0"), None, STUDY_FILE,
                            ["effect 'capillary_pressure' strength 50.0", "allowed [0, 10]"]),
    "no experiments": (lambda t: t[: t.index("[[experiment]]")], None, STUDY_FILE,
                       ["no experiments", "[[experiment]]"]),
    "no calibration role": (_edit('role = "calibration"', 'role = "heldout"'), None, STUDY_FILE,
                            ["no experiment has role 'calibration'", "calibration, heldout, predict"]),
    # --- an experiment table ---
    "unknown experiment key": (_edit('rate = "0.5 ml/min"', 'rates = "0.5 ml/min"'), None, STUDY_FILE,
                               ["[[experiment]] 0: unknown key(s) ['rates']", "'rate', 'schedule'"]),
    "wrong role name": (_edit('role = "calibration"', 'role = "training"'), None, STUDY_FILE,
                        ["field 'role' = 'training'", "allowed roles: calibration, heldout, predict"]),
    "duplicate names": (lambda t: t + t[t.index("[[experiment]]"):], None, STUDY_FILE,
                        ["field 'name' 'core7' is used by an earlier experiment", "unique"]),
    "bad name": (_edit('name = "core7"', 'name = "core 7"'), None, STUDY_FILE,
                 ["field 'name'", "letters, digits, '_', '.', '-'"]),
    "missing data key": (_edit('data = "core7.csv"\n', ""), None, STUDY_FILE,
                         ["field 'data' must be the path of a CSV or netCDF file"]),
    "missing data file": (_edit('data = "core7.csv"', 'data = "core9.csv"'), None, "core9.csv",
                          ["field 'data': no such file"]),
    "unknown core key": (_edit('length = "30 cm"', 'lenght = "30 cm"'), None, STUDY_FILE,
                         ["[experiment.core]: unknown key(s) ['lenght']",
                          "['length', 'diameter', 'porosity', 'permeability', 'swi']"]),
    "unknown length unit": (_edit('length = "30 cm"', 'length = "0.0015 furlong"'), None, STUDY_FILE,
                            ["field 'core.length'", "unknown unit 'furlong'", "allowed units: m, cm, mm, in, ft"]),
    "length without units": (_edit('length = "30 cm"', "length = 0.3"), None, STUDY_FILE,
                             ["field 'core.length'", "has no units", "m, cm, mm, in, ft"]),
    "geometry disagrees with the data": (_edit('length = "30 cm"', 'length = "25 cm"'), None, STUDY_FILE,
                                         ["field 'core.length' is given twice", "study file '25 cm'",
                                          "data file", "attr 'core_length_m' = 0.3"]),
    "porosity out of bounds": (_edit('length = "30 cm"', 'length = "30 cm"\nporosity = "0.9"'), None, STUDY_FILE,
                               ["field 'core.porosity' = 0.9", "allowed [0.01, 0.6] 1"]),
    "permeability missing everywhere": (_edit('permeability = "350 mD"\n', ""), None, STUDY_FILE,
                                        ["field 'core.permeability' is missing", "permeability_md",
                                         "it has no default"]),
    "rate missing everywhere": (_edit('rate = "0.5 ml/min"\n', ""), _edit("# rate_ml_min: 0.5\n", ""), STUDY_FILE,
                                ["field 'rate' is missing", "ml/min, ml/h, ft/day", "no default"]),
    "unknown rate unit": (_edit('rate = "0.5 ml/min"', 'rate = "0.5 gal/min"'), None, STUDY_FILE,
                          ["field 'rate'", "unknown unit 'gal/min'", "ml/min", "ft/day"]),
    "schedule longer than the data": (_edit("pv = 1.0, salinity_ppm", "pv = 3.0, salinity_ppm"), None, STUDY_FILE,
                                      ["schedule (5 PV) is longer than the data", "ends at 3 PV",
                                       "allowed data end [4.5, 5] PV"]),
    "schedule shorter than the data": (_edit("pv = 1.0, salinity_ppm", "pv = 0.5, salinity_ppm"), None,
                                       STUDY_FILE, ["runs to 3 PV, past the end of the schedule (2.5 PV)",
                                                    "allowed data end"]),
    "schedule from data without one": (lambda t: t[: t.index("schedule = [")] + 'schedule = "from data"\n'
                                       + t[t.index("[experiment.core]"):], None, STUDY_FILE,
                                       ["field 'schedule' = 'from data'", "holds no schedule",
                                        "Table 2.5 name (BCF1, BCF2, BCF3)"]),
    "slug with negative PV": (_edit("pv = 1.2,", "pv = -1.2,"), None, STUDY_FILE,
                              ["field 'schedule'", "slug 0 ('WF'): field 'pv'", "a list of slugs"]),
    "missing schedule file": (lambda t: t[: t.index("schedule = [")] + 'schedule = "flood.toml"\n'
                              + t[t.index("[experiment.core]"):], None, "flood.toml",
                              ["field 'schedule'", "schedule file", "no such file"]),
    "unknown fluid": (_edit('VIS1 = "1.0 cP"', 'VIS3 = "1.0 cP"'), None, STUDY_FILE,
                      ["[experiment.fluids]: unknown key(s) ['VIS3']", "['VIS1', 'VIS2', 'C50', 'C60']"]),
    "unknown viscosity unit": (_edit('VIS1 = "1.0 cP"', 'VIS1 = "0.01 poise"'), None, STUDY_FILE,
                               ["field 'fluids.VIS1'", "unknown unit 'poise'", "allowed units: cP"]),
    "unknown measurement field": (_edit("dead_volume_ml = 0.5", "dead_volume = 0.5"), None, STUDY_FILE,
                                  ["[experiment.measurement]: unknown key(s) ['dead_volume']", "'dead_volume_ml'"]),
    "measurement out of range": (_edit("dead_volume_ml = 0.5", "pressure_ar1 = 1.5"), None, STUDY_FILE,
                                 ["[experiment.measurement]", "'pressure_ar1' = 1.5", "allowed [0, 1) 1"]),
    "measurement with units text": (_edit("dead_volume_ml = 0.5", 'dead_volume_ml = "0.5 ml"'), None, STUDY_FILE,
                                    ["field 'measurement.dead_volume_ml' must be a number in ml"]),
    "measurement disagrees with the data": (_edit("dead_volume_ml = 0.5", "dead_volume_ml = 0.5\ntube_pv = 0.05"),
                                            _edit("# units: dp=psi", "# units: dp=psi\n# noise_tube_pv: 0.25"),
                                            STUDY_FILE, ["field 'measurement.tube_pv' is given twice",
                                                         "study file 0.05 PV", "attr 'noise_tube_pv' = 0.25"]),
    "pore volume disagrees with the core": (None, _edit("# units: dp=psi", "# units: dp=psi\n# pore_volume_ml: 90"),
                                            DATA_FILE, ["attr 'pore_volume_ml' = 90 ml disagrees with the core",
                                                        "within 1%"]),
    # --- the data file (CSV) ---
    "decreasing recovery": (None, lambda t: t.replace("1.5,2.6,0.3,0.3", "1.5,2.6,0.3,0.2"), DATA_FILE,
                            ["line 14, column 'recovery'", "decreasing recovery", ">= the previous tube's"]),
    "negative dp": (None, lambda t: t.replace("1.5,2.6,", "1.5,-2.6,"), DATA_FILE,
                    ["line 14, column 'dp'", "negative dp", "allowed range [0, inf] Pa"]),
    "absurd PV": (None, lambda t: t.replace("\n3,", "\n3000,"), DATA_FILE,
                  ["column 'pv'", "absurd PV", "[0, 1000] PV"]),
    "binary data file": (None, "binary", DATA_FILE, ["binary file", "UTF-8 CSV text"]),
    "UTF-16 data file": (None, "utf16", DATA_FILE, ["UTF-16 encoded", "UTF-8"]),
    "empty data file": (None, lambda t: "", DATA_FILE, ["empty file", "CSV coreflood"]),
    "unknown unit in the CSV header": (None, _edit("# core_diameter: 1.5 in", "# core_diameter: 1.5 inch"),
                                       DATA_FILE, ["header key 'core_diameter'", "unknown unit 'inch'",
                                                   "m, cm, mm, in, ft"]),
    "core value twice in the CSV header": (None, _edit("# core_length_m: 0.30", "# core_length_m: 0.30\n"
                                                       "# core_length: 30 cm"), DATA_FILE,
                                           ["line 3, header key 'core_length'", "already given on line 2"]),
    "core value out of range in the CSV header": (None, _edit("# swi: 0.28", "# swi: 128 %"), DATA_FILE,
                                                  ["attr 'swi' = 1.28", "allowed [0, 1] 1"]),
    # --- the data file (netCDF) ---
    "garbage netCDF": (NC_STUDY, "garbage-nc", "core7.nc", ["not a readable netCDF file", "docs/data.md"]),
    "netCDF with a broken schedule attr": (NC_STUDY, _netcdf({"schedule": '{"name": "x", "slugs": [{"pv": 1.0,'}),
                                           "core7.nc", ["attr 'schedule' is not valid JSON", "\"slugs\""]),
    "netCDF schedule with a negative slug PV": (NC_STUDY, _netcdf({"schedule": json.dumps(
        {"name": "x", "slugs": [{"pv": -3.0, "salinity_ppm": 9400.0}]})}), "core7.nc",
        ["attr 'schedule'", "slug 0", "field 'pv'"]),
    "netCDF with a negative pore volume": (NC_STUDY, _netcdf({"pore_volume_ml": -71.0, "schedule": _GOOD_SCHEDULE}),
                                           "core7.nc", ["attr 'pore_volume_ml' = -71.0", "allowed (0, inf) ml"]),
    "netCDF core attr in other units": (NC_STUDY, _netcdf({"core_length_m_units": "cm"}), "core7.nc",
                                        ["attr 'core_length_m_units' = 'cm'", "in 'm' only"]),
    "netCDF with decreasing recovery": (NC_STUDY, _netcdf(recovery=[0.05 * k for k in range(1, 12)] + [0.3]),
                                        "core7.nc", ["variable 'recovery' decreases at index 11",
                                                     "recovery[i] >= recovery[i-1]"]),
}


def _apply(edit, text, path):
    if edit == "utf16":
        path.write_bytes(text.encode("utf-16"))
    elif edit == "binary":
        path.write_bytes(b"\x89HDF\r\n\x1a\n\x00\x00\x00\x00" + bytes(range(256)))
    elif edit == "garbage-nc":
        path.write_bytes(b"this is not a netCDF file\n")
    elif callable(edit):
        path.write_text(edit(text))
    else:
        path.write_text(text)


def _project(tmp_path, study_edit, data_edit):
    path = write_project(tmp_path)
    if data_edit is not None and not isinstance(data_edit, str) and getattr(data_edit, "__name__", "") == "write":
        data_edit(tmp_path)
    elif data_edit == "garbage-nc":
        _apply(data_edit, "", tmp_path / "core7.nc")
    else:
        _apply(data_edit, data_text(), tmp_path / DATA_FILE)
    _apply(study_edit, STUDY, path)
    return path


def test_there_are_at_least_40_cases():
    assert len(CASES) >= 40


@pytest.fixture
def no_simulation(monkeypatch):
    def forbidden(*args, **kwargs):
        raise AssertionError("a simulation started while validating a study")
    monkeypatch.setattr(kernel_module, "run_kernel", forbidden)


@pytest.mark.parametrize("case", list(CASES))
def test_malformed_study_gets_one_clear_error(tmp_path, case, no_simulation, capsys):
    study_edit, data_edit, named, fragments = CASES[case]
    path = _project(tmp_path, study_edit, data_edit)
    with pytest.raises(StudyError) as err:
        load_study(path)
    message = str(err.value)
    assert named in message, message
    for fragment in fragments:
        assert fragment in message, (fragment, message)
    assert spflow.cli.main(["check", str(path)]) == 2
    captured = capsys.readouterr()
    assert captured.err.startswith("spflow: error: ") and "Traceback" not in captured.err
    assert captured.err.count("\n") == 1 and named in captured.err


def test_missing_study_file_exits_2(tmp_path, capsys):
    assert spflow.cli.main(["check", str(tmp_path / "nowhere.toml")]) == 2
    assert "nowhere.toml': no such file" in capsys.readouterr().err
