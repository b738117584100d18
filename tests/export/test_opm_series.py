"""An OPM run as a ``simulate()``-like series goes through spflow's measurement chain (lab-like data from OPM)."""

import shutil

import numpy as np
import pytest

from spflow.export.eclipse_summary import read_summary
from spflow.export.opm_deck import write_opm_deck
from spflow.export.opm_run import run_opm, summary_to_series
from spflow.io.format import check_coreflood
from spflow.plugins.forward.schedule import Schedule, Slug
from spflow.synthetic.measurement import measure
from spflow.synthetic.noise_model import NoiseModel

pytestmark = pytest.mark.skipif(shutil.which("flow") is None,
                                reason="OPM Flow ('flow') is not on PATH: apt-get install libopm-simulators-bin")

OFF = {"shear_thinning": 0.0, "dispersion": 0.0, "capillary_desaturation": 0.0}


def test_series_and_coreflood_forms_agree_and_feed_the_measurement_chain(tmp_path):
    sched = Schedule((Slug("W", 0.4, 9400.0), Slug("P", 0.6, 9400.0, 0.0, 1200.0), Slug("EWF", 0.4, 9400.0)), "s")
    deck = write_opm_deck(tmp_path / "S.DATA", sched, None, OFF, cells=30, pv_step=0.01, log=lambda m: None)
    tubes = run_opm(deck, tmp_path / "run")
    series = summary_to_series(read_summary(tmp_path / "run" / "S.SMSPEC", tmp_path / "run" / "S.UNSMRY"), deck)
    assert series.pv.values[0] == 0.0 and series.recovery.values[0] == 0.0
    np.testing.assert_allclose(series.recovery.values[1:], tubes.recovery.values)
    np.testing.assert_allclose(series.dp.values[1:], tubes.dp.values)
    # some polymer is produced, less than injected (adsorption retains part of it)
    injected_pv_ppm = 0.6 * 1200.0
    produced = np.sum(np.diff(series.pv.values) * (1 - series.oil_cut.values[1:]) * series.c_polymer_out.values[1:])
    assert 0.0 < produced < injected_pv_ppm
    lab = measure(series, NoiseModel.exact(tube_pv=0.05, pressure_interval_pv=0.02), 0, experiment="s",
                  source="OPM Flow", empty_tubes="limit")
    check_coreflood(lab, "OPM lab-like data")
    # tubes of 0.05 PV: the cumulative oil read in tubes equals OPM's recovery at the tube ends
    np.testing.assert_allclose(lab.recovery.values, np.interp(lab.pv_tube_end.values, series.pv.values,
                                                              series.recovery.values), atol=2e-3)
