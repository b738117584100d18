"""A CSV and a netCDF file holding the same coreflood and core metadata load into equal Datasets and attrs, and
give equal studies."""

import numpy as np
import pytest

from spflow.io import load_coreflood
from spflow.io.format import build_coreflood, schedule_json
from spflow.study import load_study

INCH = 0.0254
PSI = 6894.757293168361
PV = np.array([0.25 * k for k in range(1, 13)])
DP_PSI = 2.0 + 0.1 * np.arange(1, 13)
CUT = np.array([0.6, 0.5, 0.4, 0.3, 0.25, 0.2, 0.15, 0.1, 0.08, 0.05, 0.03, 0.02])
SLUGS = [{"name": "WF", "pv": 1.2, "salinity_ppm": 9400.0},
         {"name": "P", "pv": 0.8, "salinity_ppm": 9400.0, "polymer_ppm": 1500.0},
         {"name": "CW", "pv": 1.0, "salinity_ppm": 9400.0}]
PORE_ML = np.pi * (1.5 * INCH) ** 2 / 4 * 0.30 * 0.19 * 1e6


def _recovery():
    return np.cumsum(CUT * 0.25 * PORE_ML) / (PORE_ML * 0.72)


def _write_csv(path):
    header = ["# experiment: core7", "# source: lab notebook 7", "# schedule: flood.toml",
              "# core_length: 30 cm", "# core_diameter: 1.5 in", "# porosity: 19 %", "# permeability: 0.35 D",
              "# swi: 0.28", "# rate: 30 ml/h", f"# pore_volume_ml: {float(PORE_ML)!r}", "# noise_dead_volume_ml: 0.5",
              "# units: dp=psi, oil_cut=%"]
    rows = [f"{float(p)!r},{float(d)!r},{float(c) * 100!r},{float(r)!r}" for p, d, c, r in zip(PV, DP_PSI, CUT, _recovery())]
    path.write_text("\n".join(header + ["pv,dp,oil_cut,recovery"] + rows) + "\n")
    toml = ['name = "flood"'] + [line for s in SLUGS for line in
                                 ["[[slugs]]"] + [f"{k} = {v!r}" if k != "name" else f'name = "{v}"'
                                                  for k, v in s.items()]]
    (path.parent / "flood.toml").write_text("\n".join(toml) + "\n")


def _write_netcdf(path):
    ds = build_coreflood(experiment="core7", source="lab notebook 7", pv=PV, dp=DP_PSI * PSI,
                         tube_start=np.concatenate(([0.0], PV[:-1])), tube_end=PV,
                         tubes={"oil_cut": CUT, "recovery": _recovery()},
                         attrs={"core_length_m": 0.30, "core_diameter_m": 1.5 * INCH, "porosity": 0.19,
                                "permeability_md": 350.0, "swi": 0.28, "qinj_ml_min": 0.5, "pore_volume_ml": PORE_ML,
                                "noise_dead_volume_ml": 0.5, "noise_dead_volume_ml_units": "ml",
                                "schedule": schedule_json({"name": "flood", "slugs": SLUGS})})
    ds.to_netcdf(path)


def _same(a, b):
    assert sorted(a.variables) == sorted(b.variables)
    for name in a.variables:
        np.testing.assert_allclose(a[name].values, b[name].values, rtol=1e-12, atol=0)
        assert a[name].dims == b[name].dims and a[name].attrs.get("units") == b[name].attrs.get("units")
    assert sorted(a.attrs) == sorted(b.attrs)
    for key, value in a.attrs.items():
        if isinstance(value, str):
            assert value == b.attrs[key], key
        else:
            assert float(value) == pytest.approx(float(b.attrs[key]), rel=1e-12), key


def test_csv_and_netcdf_with_the_same_data_load_equal(tmp_path):
    _write_csv(tmp_path / "core7.csv")
    _write_netcdf(tmp_path / "core7.nc")
    csv, nc = load_coreflood(tmp_path / "core7.csv"), load_coreflood(tmp_path / "core7.nc")
    _same(csv, nc)
    assert csv.attrs["core_diameter_m_units"] == "m" and csv.attrs["qinj_ml_min_units"] == "ml/min"


STUDY = '''version = 1
[parameters.calibrated]
HBNC71 = [0.01, 0.02]
[[experiment]]
name = "core7"
role = "calibration"
data = "{data}"
'''


def test_studies_on_the_csv_and_the_netcdf_are_equal(tmp_path):
    _write_csv(tmp_path / "core7.csv")
    _write_netcdf(tmp_path / "core7.nc")
    studies = {}
    for suffix in ("csv", "nc"):
        path = tmp_path / f"{suffix}.toml"
        path.write_text(STUDY.format(data=f"core7.{suffix}"))
        studies[suffix] = load_study(path)
    csv, nc = (studies[k].experiments[0] for k in ("csv", "nc"))
    assert csv.model_params() == pytest.approx(nc.model_params(), rel=1e-12)
    assert csv.schedule == nc.schedule and csv.noise_model() == nc.noise_model()
    assert csv.sources == nc.sources
    _same(csv.observations(), nc.observations())
    assert [d.to_dict() for d in studies["csv"].defaults_taken] == [d.to_dict() for d in studies["nc"].defaults_taken]
