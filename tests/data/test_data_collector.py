"""Fraction collector and outlet dead volume: tube mass balance against the simulator's own recovery (a
conservation law), lab arithmetic of oil cut and recovery, and the exact PV shift of a dead volume."""

import math

import numpy as np
import pytest

from spflow.plugins.forward.simulate import simulate
from spflow.synthetic import NoiseModel, make_coreflood
from spflow.synthetic.dead_volume import delay
from spflow.synthetic.fraction_collector import tube_amounts, tube_edges

CELLS, STEP = 60, 0.005


@pytest.fixture(scope="module")
def clean():
    return simulate("BCF1", cells=CELLS, pv_step=STEP)


def _ooip_ml(attrs):
    # pi D^2/4 L phi (1 - Swi), in ml, from the simulator's resolved parameters
    return math.pi * attrs["param_DIAMETER"] ** 2 / 4 * attrs["param_LENGTH"] * attrs["param_PORO"] \
        * (1 - attrs["param_SWI"]) * 1e6


def test_tube_oil_volumes_add_up_to_recovery_times_ooip(clean):
    ooip = _ooip_ml(clean.attrs)
    exact = make_coreflood("BCF1", cells=CELLS, pv_step=STEP, noise=NoiseModel.exact())
    end = exact["pv_tube_end"].values[-1]
    produced = np.interp(end, clean["pv"].values, clean["recovery"].values) * ooip
    assert exact.attrs["ooip_ml"] == pytest.approx(ooip, rel=1e-12)
    assert exact["oil_volume"].sum().item() == pytest.approx(produced, rel=1e-9)

    r = 0.1
    noisy = make_coreflood("BCF1", cells=CELLS, pv_step=STEP, noise=NoiseModel.exact(oil_resolution_ml=r), seed=4)
    n = noisy.sizes["pv_tube"]
    error = noisy["oil_volume"].sum().item() - produced
    assert abs(error) <= n * r / 2  # every reading is within half a graduation
    assert abs(error) <= 5 * r * math.sqrt(n / 12)  # ... and the errors are independent
    per_tube = noisy["oil_volume"].values - exact["oil_volume"].values
    assert np.all(np.abs(per_tube) <= r / 2 + 1e-12) and np.any(per_tube != 0.0)
    assert noisy["recovery"].values[-1] * noisy.attrs["ooip_ml"] == pytest.approx(noisy["oil_volume"].sum().item())


def test_oil_cut_and_recovery_are_computed_from_readings_as_a_lab_does():
    ds = make_coreflood("BCF1", cells=CELLS, pv_step=STEP, seed=9)
    tube_ml = ds.attrs["noise_tube_pv"] * ds.attrs["pore_volume_ml"]
    oil = ds["oil_volume"].values
    np.testing.assert_allclose(ds["oil_cut"].values, oil / tube_ml, rtol=1e-14)
    np.testing.assert_allclose(ds["recovery"].values, np.cumsum(oil) / ds.attrs["ooip_ml"], rtol=1e-14)
    np.testing.assert_allclose(ds["pv_tube_end"] - ds["pv_tube_start"], ds.attrs["noise_tube_pv"], atol=1e-12)


def test_tube_amounts_integrate_a_piecewise_constant_signal_exactly():
    pv = np.array([0.0, 0.3, 0.7, 1.0])
    values = np.array([9.0, 2.0, 5.0, 1.0])  # values[0] is the pv = 0 value, not integrated
    amounts = tube_amounts(pv, values, tube_edges(1.0, 0.25))
    expected = [0.25 * 2, 0.05 * 2 + 0.2 * 5, 0.2 * 5 + 0.05 * 1, 0.25 * 1]
    np.testing.assert_allclose(amounts, expected, rtol=1e-14)


def test_dead_volume_shifts_breakthrough_by_exactly_v_dead():
    pv = np.linspace(0.0, 2.0, 201)
    signal = np.where(pv > 0.63, 1.0, 0.0)
    for v_dead in (0.0, 0.037, 0.25):
        pv_out, out = delay(pv, signal, v_dead, fill=0.0)
        assert pv_out[np.argmax(out >= 0.5)] - pv[np.argmax(signal >= 0.5)] == pytest.approx(v_dead, abs=1e-12)


def test_dead_volume_delays_every_collected_signal_by_whole_tubes():
    tube = 0.01
    base = make_coreflood("BCF1", cells=CELLS, pv_step=STEP, noise=NoiseModel.exact(tube_pv=tube))
    v_ml = 0.1 * base.attrs["pore_volume_ml"]  # 0.1 PV = 10 tubes
    late = make_coreflood("BCF1", cells=CELLS, pv_step=STEP, noise=NoiseModel.exact(tube_pv=tube,
                                                                                    dead_volume_ml=v_ml))
    assert late.attrs["dead_volume_pv"] == pytest.approx(0.1, rel=1e-12)
    for name in ("oil_cut", "c_polymer_out", "c_surfactant_out", "salinity_out"):
        np.testing.assert_allclose(late[name].values[10:], base[name].values[:-10], rtol=1e-7, atol=1e-9)
    assert np.all(late["oil_cut"].values[:10] == 0.0)  # the lines hold brine, no oil
    for ds in (base, late):  # polymer breakthrough: first tube above half the injected 3300 ppm
        ds.attrs["bt"] = ds["pv_tube_end"].values[np.argmax(ds["c_polymer_out"].values > 1650.0)]
    assert late.attrs["bt"] - base.attrs["bt"] == pytest.approx(0.1, abs=1e-9)
    np.testing.assert_array_equal(late["dp"].values, base["dp"].values)  # pressure is not delayed


def test_tubes_without_water_have_no_assay_or_its_zero_water_limit():
    """Before water breakthrough (oil cut 1 at the outlet) a tube holds no water: lab data has no polymer or salinity
    assay there (NaN); a prediction gets the zero-water limit -- no polymer, the initial brine's salinity."""
    from spflow.synthetic.measurement import measure

    # connate water at its residual saturation (no trapping-number shift): the water is immobile until the front
    sim = simulate("BCF1", {"SWI": 0.2, "S1RWC": 0.2}, cells=30, pv_step=0.01,
                   effects={"capillary_desaturation": 0.0})
    noise = NoiseModel.exact(tube_pv=0.05)
    oil_only = sim.oil_cut.values[sim.pv.values <= 0.1]
    assert np.all(oil_only > 1.0 - 1e-14)  # the premise: the first 0.1 PV is pure oil (to round-off)
    lab = measure(sim, noise, 0, experiment="BCF1", source="test")
    pred = measure(sim, noise, 0, experiment="BCF1", source="test", empty_tubes="limit")
    first = lab.pv_tube.values < 0.1
    assert np.all(np.isnan(lab.c_polymer_out.values[first])) and np.all(np.isnan(lab.salinity_out.values[first]))
    np.testing.assert_array_equal(pred.c_polymer_out.values[first], 0.0)
    np.testing.assert_allclose(pred.salinity_out.values[first], sim.salinity_out.values[0])
    wet = ~np.isnan(lab.c_polymer_out.values)
    np.testing.assert_array_equal(pred.c_polymer_out.values[wet], lab.c_polymer_out.values[wet])
    with pytest.raises(ValueError, match=r"empty_tubes must be one of \['missing', 'limit'\]"):
        measure(sim, noise, 0, experiment="BCF1", source="test", empty_tubes="zero")
