"""A new user in an empty directory outside the repository: corefloods of a core unlike Berea's (0.30 m x 1.5 in,
porosity 0.19, 0.5 ml/min, Swi 0.28) made by the twin generator -- a polymer-only flood as a lab CSV (dp in psi,
core data in the header, no permeability, no measurement chain) and an SP flood as netCDF -- then `spflow init`,
an edit, `spflow check`: every default is printed, and the values are the user's."""

from pathlib import Path

import numpy as np
import pytest

import spflow.cli
from spflow.synthetic import NoiseModel, make_coreflood

PSI = 6894.757293168361
INCH = 0.0254
CORE = {"LENGTH": 0.30, "DIAMETER": 1.5 * INCH, "PORO": 0.19, "PERM": 350.0, "QINJ": 0.5, "SWI": 0.28,
        "S1RWC": 0.28}
POLYMER = [{"name": "WF", "pv": 1.2, "salinity_ppm": 9400.0},
           {"name": "P", "pv": 0.8, "salinity_ppm": 9400.0, "polymer_ppm": 1500.0},
           {"name": "CW", "pv": 1.0, "salinity_ppm": 9400.0}]
SP = [{"name": "WF", "pv": 1.0, "salinity_ppm": 9400.0},
      {"name": "SP", "pv": 0.5, "salinity_ppm": 9400.0, "surfactant_ppm": 6780.0, "polymer_ppm": 2000.0},
      {"name": "P", "pv": 0.8, "salinity_ppm": 9400.0, "polymer_ppm": 2000.0},
      {"name": "CW", "pv": 0.7, "salinity_ppm": 9400.0}]
CHAIN = NoiseModel(dead_volume_ml=0.5, pressure_offset_pa=0.0, pressure_drift_pa_per_pv=0.0, tube_pv=0.1,
                   pressure_interval_pv=0.05)


def _lab_csv(ds, path):
    """The twin as a lab would type it: dp in psi, tubes as oil cut and recovery, core data in the header."""
    rows = {}
    for pv, dp in zip(ds["pv"].values, ds["dp"].values):
        rows.setdefault(round(float(pv), 9), {})["dp"] = float(dp) / PSI
    for i, end in enumerate(ds["pv_tube_end"].values):
        rows.setdefault(round(float(end), 9), {}).update(oil_cut=float(ds["oil_cut"].values[i]),
                                                        recovery=float(ds["recovery"].values[i]))
    lines = ["# experiment: poly7", "# core_length_m: 0.30", "# core_diameter: 1.5 in", "# porosity: 0.19",
             "# swi: 0.28", "# rate_ml_min: 0.5", "# units: dp=psi", "pv,dp,oil_cut,recovery"]
    for pv in sorted(rows):
        cells = [rows[pv].get(c) for c in ("dp", "oil_cut", "recovery")]
        lines.append(",".join([repr(pv)] + ["" if v is None else repr(v) for v in cells]))
    path.write_text("\n".join(lines) + "\n")


@pytest.fixture
def user_dir(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert not (Path.cwd() / "pyproject.toml").exists()
    poly = make_coreflood({"name": "poly", "slugs": POLYMER}, CORE, noise=CHAIN, seed=7, cells=20, pv_step=0.01)
    _lab_csv(poly, tmp_path / "poly7.csv")
    sp = make_coreflood({"name": "sp", "slugs": SP}, CORE, noise=CHAIN, seed=8, cells=20, pv_step=0.01,
                        experiment="sp8")
    sp.to_netcdf(tmp_path / "sp8.nc")
    return tmp_path


def test_init_edit_check(user_dir, capsys):
    assert spflow.cli.main(["init", "study", "--data", "poly7.csv", "sp8.nc"]) == 0
    out = capsys.readouterr().out
    assert "DEFAULT roles: poly7 calibration, sp8 heldout (every file calibrates except the last, held out)" in out
    assert "DEFAULT experiment 'poly7': core.permeability = 700 mD (not in the data file)" in out
    assert "DEFAULT experiment 'poly7': schedule = one 9400 ppm waterflood of 3 PV" in out
    text = (user_dir / "study" / "study.toml").read_text()
    assert text.count("  # DEFAULT:") == 6  # calibrated space, effects, 2 roles, permeability, schedule
    # valid and runnable as written
    assert spflow.cli.main(["check", "study/study.toml"]) == 0
    capsys.readouterr()

    # the user edits what they know: permeability, the polymer flood's slugs and the rig's measurement chain
    text = text.replace('permeability = "700 mD"  # DEFAULT', 'permeability = "0.35 D"  # measured')
    start = text.index("schedule = [{ name = \"WF\", pv = 3")
    end = text.index("\n", start)
    text = text[:start] + ('schedule = [{ pv = 1.2, salinity_ppm = 9400 }, { pv = 0.8, salinity_ppm = 9400, '
                           'polymer_ppm = 1500 }, { pv = 1.0, salinity_ppm = 9400 }]') + text[end:]
    first = text.index("[experiment.measurement]")
    text = text[:first] + ("[experiment.measurement]\ndead_volume_ml = 0.5\ntube_pv = 0.1\npressure_interval_pv = "
                           "0.05\npressure_offset_pa = 0.0\npressure_drift_pa_per_pv = 0.0\n")\
        + text[text.index("\n", first) + 1:]
    (user_dir / "study" / "study.toml").write_text(text)

    assert spflow.cli.main(["check", "study/study.toml"]) == 0
    out = capsys.readouterr().out
    defaults = [line.strip() for line in out.splitlines() if line.strip().startswith("DEFAULT")]
    expected = {f"DEFAULT experiment 'poly7': measurement.{f} = {v}" for f, v in [
        ("pressure_relative", "0.02 1"), ("pressure_ar1", "0.8 1"), ("oil_resolution_ml", "0.1 ml"),
        ("concentration_relative", "0.03 1")]}
    expected |= {f"DEFAULT experiment '{e}': fluids.{k} = {v}" for e in ("poly7", "sp8") for k, v in
                 [("VIS1", "1 cP"), ("VIS2", "13.8 cP"), ("C50", "0.145 meq/ml"), ("C60", "0.0097 meq/ml")]}
    assert {line.split(" (")[0] for line in defaults} == expected
    assert "study OK: 2 experiment(s), 12 default(s) taken" in out

    study = spflow.load_study("study/study.toml")
    poly, sp = study.experiments
    assert poly.model_params() == pytest.approx({k: CORE[k] for k in ("LENGTH", "DIAMETER", "PORO", "PERM", "SWI",
                                                                      "QINJ")})
    assert poly.noise_model() == CHAIN and sp.noise_model() == CHAIN
    assert [s.polymer_ppm for s in poly.schedule.slugs] == [0.0, 1500.0, 0.0]
    assert sp.schedule.slugs[1].surfactant_ppm == 6780.0 and sp.role == "heldout"
    first_row = (user_dir / "poly7.csv").read_text().splitlines()[8].split(",")
    np.testing.assert_allclose(poly.observations()["dp"].values[0], float(first_row[1]) * PSI, rtol=1e-12)


def test_init_refuses_to_overwrite_and_names_bad_data(user_dir, capsys):
    assert spflow.cli.main(["init", "study", "--data", "poly7.csv"]) == 0
    assert spflow.cli.main(["init", "study", "--data", "poly7.csv"]) == 2
    assert "exists" in capsys.readouterr().err
    (user_dir / "bad.csv").write_bytes("pv,dp\n0.1,100\n".encode("utf-16"))
    assert spflow.cli.main(["init", "other", "--data", "bad.csv"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("spflow: error:") and "bad.csv" in err and "UTF-16" in err


def test_init_without_data_writes_the_bundled_study(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert spflow.cli.main(["init", "bundled"]) == 0
    assert "DEFAULT no --data: the bundled study BCF1-BCF3" in capsys.readouterr().out
    assert sorted(p.name for p in (tmp_path / "bundled").iterdir()) == ["BCF1.nc", "BCF2.nc", "BCF3.nc", "study.toml"]
    assert spflow.cli.main(["check", "bundled/study.toml"]) == 0
    assert "study OK: 3 experiment(s), 0 default(s) taken" in capsys.readouterr().out
