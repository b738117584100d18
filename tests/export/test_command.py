"""``spflow export opm`` / ``spflow compare opm`` from the command line."""

import shutil

import numpy as np
import pytest
import xarray as xr

from spflow.cli import main

from .deck_text import table

SCHEDULE = """name = "cli"
[[slugs]]
pv = 0.3
salinity_ppm = 9400
[[slugs]]
pv = 0.4
salinity_ppm = 9400
polymer_ppm = 800
[[slugs]]
pv = 0.3
salinity_ppm = 9400
"""
PARAMS = """[parameters]
AP1 = 20.0
[effects]
shear_thinning = 0
dispersion = 0
"""


@pytest.fixture
def files(tmp_path):
    (tmp_path / "s.toml").write_text(SCHEDULE)
    (tmp_path / "p.toml").write_text(PARAMS)
    return tmp_path


def test_export_writes_the_deck_with_the_file_parameters(files, capsys):
    out = files / "deck"
    rc = main(["export", "opm", "--schedule", str(files / "s.toml"), "--params", str(files / "p.toml"),
               "--effect", "capillary_desaturation=0", "--out", str(out), "--cells", "20"])
    assert rc == 0
    assert "scaled by" in capsys.readouterr().out
    c, mult = np.array(table((out / "CORE.DATA").read_text(), "PLYVISC")).T
    x = c[-1] / 10.0
    assert np.isclose(c[-1], 0.8)
    # AP1 = 20 from the file, AP2 = 0, AP3 = 155 defaults; C_SEP of 9400 ppm = 0.145 + 0 x 0.0097 meq/ml, SSLOPE -0.76
    assert np.isclose(mult[-1], 1 + (20.0 * x + 155.0 * x**3) * 0.145 ** -0.76, rtol=1e-9)


def test_export_time_step_cap_default_value_and_none(files, capsys):
    args = ["export", "opm", "--schedule", str(files / "s.toml"), "--params", str(files / "p.toml"),
            "--effect", "capillary_desaturation=0", "--cells", "20"]
    assert main([*args, "--out", str(files / "default")]) == 0
    assert "time steps capped at 0.0005 PV" in capsys.readouterr().out
    assert "TUNING" in (files / "default" / "CORE.DATA").read_text()
    assert main([*args, "--max-step-pv", "0.002", "--out", str(files / "wide")]) == 0
    assert "time steps capped at 0.002 PV" in capsys.readouterr().out
    assert main([*args, "--max-step-pv", "none", "--out", str(files / "free")]) == 0
    assert "no cap on OPM's time steps" in capsys.readouterr().out
    assert "TUNING" not in (files / "free" / "CORE.DATA").read_text()
    assert main([*args, "--max-step-pv", "-1", "--out", str(files / "bad")]) == 2
    assert "max_step_pv" in capsys.readouterr().err


def test_export_refuses_missing_mechanisms_with_a_clear_message(files, capsys):
    rc = main(["export", "opm", "--schedule", str(files / "s.toml"), "--params", str(files / "p.toml"),
               "--out", str(files / "x")])
    assert rc == 2
    err = capsys.readouterr().err
    assert "capillary_desaturation" in err and "--approximate" in err
    assert not (files / "x" / "CORE.DATA").exists()


def test_export_shear_thinning_at_a_chosen_saturation(files, capsys):
    out = files / "shear"
    rc = main(["export", "opm", "--schedule", str(files / "s.toml"), "--params", str(files / "p.toml"),
               "--effect", "capillary_desaturation=0", "--effect", "shear_thinning=1", "--approximate",
               "--shear-sw", "0.6", "--out", str(out), "--cells", "20"])
    assert rc == 0
    printed = capsys.readouterr().out
    assert "APPROXIMATION shear_thinning_saturation" in printed and "Sw* = 0.6" in printed
    assert "PLYSHLOG" in (out / "CORE.DATA").read_text()


def test_bad_effect_argument(files, capsys):
    rc = main(["export", "opm", "--schedule", "BCF1", "--effect", "shear_thinning", "--out", str(files / "y")])
    assert rc == 2
    assert "NAME=VALUE" in capsys.readouterr().err


@pytest.mark.skipif(shutil.which("flow") is None, reason="OPM Flow ('flow') is not on PATH")
def test_compare_writes_table_figure_and_coreflood_files(files, capsys):
    out = files / "cmp"
    rc = main(["compare", "opm", "--schedule", str(files / "s.toml"), "--params", str(files / "p.toml"),
               "--effect", "capillary_desaturation=0", "--out", str(out), "--cells", "30", "--pv-step", "0.02"])
    assert rc == 0
    printed = capsys.readouterr().out
    assert "recovery at the end" in printed and "polymer effluent midpoint" in printed
    for name in ("comparison.csv", "comparison.png", "opm.nc", "spflow.nc"):
        assert (out / name).is_file()
    opm = xr.open_dataset(out / "opm.nc")
    ref = xr.open_dataset(out / "spflow.nc")
    assert set(opm.attrs["measured"].split()) == {"dp", "oil_cut", "recovery"}
    assert abs(float(opm.recovery[-1]) - float(ref.recovery[-1])) < 0.01
