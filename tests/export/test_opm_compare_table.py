"""``comparison_table``'s Δp at a slug end is the left limit on both sides, also across a rate step.

Synthetic series, no OPM Flow needed: Δp = 100 Pa/PV x pv at 1 ml/min until the slug ends at 1.4 PV, then twice
that at 2 ml/min. OPM's report point at the end is rounded to whole seconds (1.3999 PV); spflow's record at 1.4 PV
holds the ending slug's value. The expected rows are written out here."""

import numpy as np
import pytest
import xarray as xr

from spflow.export.opm_compare import comparison_table
from spflow.plugins.forward.schedule import Schedule, Slug

END = 1.4
SCHED = Schedule((Slug("W", 0.6, 9400.0, rate_ml_min=1.0), Slug("P", 0.8, 9400.0, 0.0, 1000.0, rate_ml_min=1.0),
                  Slug("EWF", 0.6, 9400.0, rate_ml_min=2.0)), "rates")


def _dp(pv: np.ndarray, left_at_end: bool) -> np.ndarray:
    rate = np.where((pv < END) | (left_at_end & np.isclose(pv, END, atol=2e-4)), 1.0, 2.0)
    return 100.0 * pv * rate


def _series(pv: np.ndarray) -> xr.Dataset:
    n = pv.size
    return xr.Dataset({"dp": ("pv", _dp(pv, True)), "recovery": ("tube", np.linspace(0, 0.5, n - 1)),
                       "c_polymer_out": ("tube", np.zeros(n - 1))},
                      coords={"pv": pv, "pv_tube": ("tube", 0.5 * (pv[1:] + pv[:-1])),
                              "pv_tube_end": ("tube", pv[1:])})


def test_dp_at_slug_ends_is_the_left_limit():
    ref_pv = np.round(np.arange(0, 201) * 0.01, 12)
    opm_pv = ref_pv.copy()
    opm_pv[140] = 1.3999  # rounded report-step lengths
    rows = {r["quantity"]: r for r in comparison_table(_series(opm_pv), _series(ref_pv), SCHED)}
    at_end = rows["dp at the end of slug 'P' (1.4 PV)"]
    assert at_end["opm"] == pytest.approx(100.0 * 1.3999)  # the report point at the end, not beyond it
    assert at_end["spflow"] == pytest.approx(100.0 * END)  # the ending slug's rate, not the next one's
    assert abs(at_end["difference"]) < 1e-3
    assert rows["dp at the end of slug 'EWF' (2 PV)"]["spflow"] == pytest.approx(2 * 100.0 * 2.0)
