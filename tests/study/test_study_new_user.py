"""A new user in an empty directory outside the repository: corefloods of a core unlike Berea's (0.30 m x 1.5 in,
porosity 0.19, 0.5 ml/min, Swi 0.28) made by the twin generator -- a polymer-only flood as a lab CSV (dp in psi,
core data in the header, no permeability, no measurement chain) and an SP flood as netCDF -- then `spflow init`,
an edit, `spflow check`: every default is printed, and the values are the user's."""

from pathlib import Path

import numpy as np
import pytest

import spflow.cli
from new_user_data import CHAIN, CORE, PSI, edited, write_user_data


@pytest.fixture
def user_dir(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert not (Path.cwd() / "pyproject.toml").exists()
    write_user_data(tmp_path)
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
    text = edited(text)
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


def test_check_lists_values_still_marked_by_init(tmp_path, capsys):
    """`spflow check` lists the values `spflow init` chose that the user has not replaced (comment lines aside)."""
    from spflow.study.command import init_markers

    study = tmp_path / "s.toml"
    study.write_text('# Values marked \'# DEFAULT:\' were chosen by init\nversion = 1\n'
                     'role = "calibration"  # DEFAULT: every file calibrates except the last\n'
                     'permeability = "250 mD"\n')
    assert init_markers(study) == ['line 3: role = "calibration"']
