"""Issue 19's round trip on a study of a core unlike Berea's (``new_user_data``: 0.30 m x 1.5 in, porosity 0.19,
0.5 ml/min, Swi 0.28, 350 mD; a polymer-only flood as a lab CSV calibrating, an SP flood as netCDF held out, both
under the documented measurement chain ``CHAIN``), whose calibrated space is not the thesis's: a group of three
Corey exponents (``n_low``), a log-scale parameter (``CRK``) and a plain one (``GAMHF``), with the truth inside the
ranges and away from the model's defaults.

(a) the chapter-3 history match of that study (its space, its roles) puts the truth inside every noise-consistent
    range (the NSGA-II stage's ``confidence_lower/upper``, in the design's columns: log10 for ``CRK``);
(b) the gap diagnosis says ``none`` on null twins of that core for three noise seeds.
(c) a CSV and a netCDF of the same data give the same diagnosis, and (d) a study that omits the measurement chain
    prints the defaults it took, are tested in ``test_study_pipelines.py``
    (``test_a_csv_and_a_netcdf_of_the_same_data_give_the_same_diagnosis``,
    ``test_a_study_that_omits_the_measurement_chain_prints_its_defaults_at_run_start``).

Twins and model share their grid (``CELLS``), so what remains is measurement noise (and, for (a), proxy error).
"""

import numpy as np
import pytest

import spflow
from spflow.core.overrides import apply_overrides
from spflow.pipelines import gap_diagnosis, history_matching
from spflow.synthetic import make_coreflood
from new_user_data import CHAIN, CORE, POLYMER, SP, lab_csv

CELLS = 20
#: the truth, in UTCHEM names: n_low = 2.4 for every phase, CRK = 0.045 (log scale), GAMHF = 80 1/s
TRUTH = {"E1WC": 2.4, "E2WC": 2.4, "E3WC": 2.4, "CRK": 0.045, "GAMHF": 80.0}
#: the truth in the design's columns, computed here: a log-scale column holds log10 of the value
TRUTH_COLUMNS = {"n_low": 2.4, "CRK": np.log10(0.045), "GAMHF": 80.0}

STUDY = """version = 1
[parameters.calibrated]
n_low = {{ names = ["E1WC", "E2WC", "E3WC"], range = [1.5, 3.0] }}
CRK = {{ range = [0.03, 0.1], scale = "log" }}
GAMHF = [50.0, 110.0]

[[experiment]]
name = "poly7"
role = "calibration"
data = "poly7.csv"
schedule = [
  {{ name = "WF", pv = 1.2, salinity_ppm = 9400 }},
  {{ name = "P", pv = 0.8, salinity_ppm = 9400, polymer_ppm = 1500 }},
  {{ name = "CW", pv = 1.0, salinity_ppm = 9400 }},
]
[experiment.core]
permeability = "350 mD"
[experiment.measurement]
{chain}

[[experiment]]
name = "sp8"
role = "heldout"
data = "sp8.nc"
schedule = "from data"
[experiment.core]
permeability = "350 mD"
"""


def write_twin_study(directory, seed: int):
    """The study and its two twins (noise seeds ``seed``, ``seed + 1``) in ``directory``; returns the study path."""
    directory.mkdir(parents=True, exist_ok=True)
    truth = {k: v for k, v in CORE.items() if k != "S1RWC"} | TRUTH  # residual water: the model's (no study key)
    poly = make_coreflood({"name": "poly", "slugs": POLYMER}, truth, noise=CHAIN, seed=seed, cells=CELLS,
                          pv_step=0.01)
    lab_csv(poly, directory / "poly7.csv")
    make_coreflood({"name": "sp", "slugs": SP}, truth, noise=CHAIN, seed=seed + 1, cells=CELLS, pv_step=0.01,
                   experiment="sp8").to_netcdf(directory / "sp8.nc")
    chain = "\n".join(f"{k} = {v!r}" for k, v in vars(CHAIN).items())
    path = directory / "study.toml"
    path.write_text(STUDY.format(chain=chain))
    return path


def test_the_study_space_reaches_the_history_match(tmp_path):
    study = spflow.load_study(write_twin_study(tmp_path, seed=7))
    assert study.experiment("poly7").core["core_length_m"] == pytest.approx(0.30)
    p = history_matching.pipeline(study=study, quick=True)
    assert p.nodes["space"].params["names"] == ["n_low", "CRK", "GAMHF"]
    assert p.nodes["space"].params["ranges"]["CRK"]["scale"] == "log"


@pytest.mark.parametrize("seed", [7, 17, 27])
def test_history_match_noise_consistent_ranges_contain_the_truth(tmp_path, seed):
    study = write_twin_study(tmp_path / "data", seed=seed)
    p = history_matching.pipeline(study=study, samples=100, cells=CELLS, generations=20, population=40, degree_max=4)
    result = spflow.run(p, cache=tmp_path / "cache", until=["calibration"])
    cal = result["calibration"]
    assert cal["param"].values.tolist() == list(TRUTH_COLUMNS)
    assert cal["utchem_names"].values.tolist() == ["E1WC E2WC E3WC", "CRK", "GAMHF"]
    assert cal["scale"].values.tolist() == ["linear", "log", "linear"]
    assert cal.attrs["training"] == "poly7" and cal["experiment"].values.tolist() == ["sp8"]
    lines = []
    for label, truth in TRUTH_COLUMNS.items():
        c = cal.sel(param=label)
        lo, hi = float(c["confidence_lower"]), float(c["confidence_upper"])
        lines.append(f"{label}: truth {truth:.4g} in [{lo:.4g}, {hi:.4g}] (prior [{float(c['prior_lower']):.4g}, "
                     f"{float(c['prior_upper']):.4g}])")
        assert lo <= truth <= hi, lines[-1]
    print("\n".join(lines) + f"\nundetermined: {cal.attrs['undetermined'] or 'none'}; held-out sigma_loss "
          f"{float(cal['sigma_loss'].isel(checkpoint=-1)):.4f}")


@pytest.mark.parametrize("seed", [11, 21, 31])
def test_gap_diagnosis_of_null_twins_of_the_core_says_none(tmp_path, seed):
    study = write_twin_study(tmp_path, seed=seed)
    p = gap_diagnosis.pipeline(study=study, cells=CELLS)
    apply_overrides(p, ['diagnosis.catalogue=["capillary_pressure", "kinetic_adsorption", "dispersion"]',
                        "diagnosis.max_nfev=15", "diagnosis.replicates=50", "diagnosis.max_effects=1"])
    gap = spflow.run(p, cache=tmp_path / "cache")["diagnosis"]
    from spflow.plugins.gap.report import summary

    info = summary(gap)
    print(f"seed {seed}: verdict {info['verdict']}, calibration chi2 p = {info['fit']['chi2_pvalue']:.3g}")
    assert info["verdict"] == "none" and info["effects"] == []
