"""A polymer flood's surfactant assay reads zero throughout and nothing injected it: it has no noise scale and
carries no information, so the diagnosis layout leaves it out (before, every polymer-flood netCDF made by the twin
generator failed the diagnosis with 'AR(1) scales must be finite and > 0'); the polymer assay stays."""

from spflow.plugins.gap.layout import make_layout
from spflow.plugins.gap.observed import load_experiments
from spflow.synthetic import NoiseModel, make_coreflood

POLYMER = [{"name": "WF", "pv": 1.0, "salinity_ppm": 9400.0},
           {"name": "P", "pv": 0.8, "salinity_ppm": 9400.0, "polymer_ppm": 1500.0},
           {"name": "CW", "pv": 1.0, "salinity_ppm": 9400.0}]


def test_a_never_injected_species_that_reads_zero_is_left_out():
    ds = make_coreflood({"name": "poly", "slugs": POLYMER}, noise=NoiseModel(), seed=1, cells=10, pv_step=0.02)
    assert float(abs(ds["c_surfactant_out"]).max()) == 0.0 and float(ds["c_polymer_out"].max()) > 0.0
    layout = make_layout(load_experiments([ds], pv_step=0.1))
    variables = {b.variable for b in layout.blocks}
    assert "c_surfactant_out" not in variables
    assert {"dp", "oil_cut", "recovery", "c_polymer_out", "salinity_out"} <= variables
