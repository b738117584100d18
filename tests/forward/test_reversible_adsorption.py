"""Reversible polymer adsorption (``ADSREV4``, effect ``reversible_polymer_adsorption``) against the analytic
single-phase Langmuir waves.

A water-filled core (SWI = 1) takes a polymer slug of ``C_J`` and a long water post-flush, without dispersion, so
the polymer obeys ``d/dt [e c + C^(c)] + dc/dx = 0`` in PV units (``e = EPHI4``, ``C^ = a c/(1 + b c)``):

* injection: a shock (Langmuir is favourable) whose effluent midpoint is at ``e + a/(1 + b C_J)`` PV;
* post-flush with a reversible fraction ``f`` of the isotherm (the irreversible part stays at ``(1 - f) C^(C_J)``):
  a rarefaction, each concentration travelling at ``1 / (e + f a/(1 + b c)^2)``, so that ``tau`` PV after the
  post-flush starts the effluent holds ``c = (sqrt(f a/(tau - e)) - 1)/b`` for
  ``e + f a/(1 + b C_J)^2 <= tau <= e + f a`` (``C_J`` before, 0 after);
* at the end: every reversibly adsorbed molecule has come out (``f = 1``: nothing left on the rock) and the
  polymer mass balance closes to round-off; irreversible adsorption (``f = 0``, the default) keeps the plateau
  ``C^(C_J)`` in every cell.
"""

from functools import lru_cache

import numpy as np
import pytest

from spflow.plugins.forward.simulate import simulate

EPHI4, AD41, B4D = 0.85, 1.0, 100.0  # B4D in 1/wt %
C_J_PPM = 1000.0
C_J = C_J_PPM / 1.0e4  # wt %
POLYMER_PV, POSTFLUSH_PV = 3.0, 12.0
PARAMS = {"SWI": 1.0, "S1RWC": 0.0, "S2RWC": 0.0, "S3RWC": 0.0, "P1RWC": 1.0, "P1RC": 1.0,
          "EPHI4": EPHI4, "AD41": AD41, "AD42": 0.0, "B4D": B4D}
EFFECTS = {"dispersion": 0.0, "permeability_reduction": 0.0, "capillary_desaturation": 0.0, "shear_thinning": 0.0,
           "polymer_adsorption": 1.0, "inaccessible_pore_volume": 1.0}
SCHEDULE = [{"pv": POLYMER_PV, "salinity_ppm": 9400.0, "polymer_ppm": C_J_PPM},
            {"pv": POSTFLUSH_PV, "salinity_ppm": 9400.0}]
PLATEAU_PPM = AD41 * C_J / (1.0 + B4D * C_J) * 1.0e4  # adsorbed per pore volume at C_J, ppm x PV/PV


@lru_cache(maxsize=None)
def flood(fraction: float, cells: int = 200, params: tuple = ()):
    return simulate(SCHEDULE, {**PARAMS, **dict(params)}, cells=cells, pv_step=0.005,
                    effects={**EFFECTS, "reversible_polymer_adsorption": fraction},
                    profiles_at=[POLYMER_PV, POLYMER_PV + POSTFLUSH_PV])


def effluent(ds):
    """Effluent polymer (ppm) at the midpoints of the output intervals (it is an interval average)."""
    pv = ds["pv"].values
    return 0.5 * (pv[1:] + pv[:-1]), ds["c_polymer_out"].values[1:]


def desorption_wave_ppm(tau, fraction):
    """Analytic effluent ``tau`` PV into the post-flush (ppm)."""
    tau = np.asarray(tau, dtype=float)
    fa = fraction * AD41
    c = np.clip((np.sqrt(fa / np.maximum(tau - EPHI4, 1e-300)) - 1.0) / B4D, 0.0, C_J)
    return np.where(tau < EPHI4 + fa / (1.0 + B4D * C_J) ** 2, C_J, c) * 1.0e4


def first_crossing(t, y, level):
    """First ``t`` where ``y`` crosses ``level`` (linear interpolation)."""
    above = y >= level
    k = int(np.flatnonzero(above != above[0])[0])
    return t[k - 1] + (level - y[k - 1]) / (y[k] - y[k - 1]) * (t[k] - t[k - 1])


@pytest.mark.parametrize("fraction", [0.0, 0.5, 1.0])
def test_adsorption_front_midpoint_is_langmuir_retardation(fraction):
    t, c = effluent(flood(fraction))
    expected = EPHI4 + AD41 / (1.0 + B4D * C_J)
    assert first_crossing(t, c, 0.5 * C_J_PPM) == pytest.approx(expected, abs=0.005)


@pytest.mark.parametrize("fraction", [0.5, 1.0])
def test_desorption_wave_on_post_flush(fraction):
    t, c = effluent(flood(fraction))
    tau = np.linspace(EPHI4 + 0.05, EPHI4 + fraction * AD41 - 0.15, 25)
    numeric = np.interp(POLYMER_PV + tau, t, c)
    exact = desorption_wave_ppm(tau, fraction)
    assert exact.max() > 0.2 * C_J_PPM and exact.min() > 0.005 * C_J_PPM  # inside the rarefaction
    np.testing.assert_allclose(numeric, exact, atol=0.03 * C_J_PPM)
    # half the injected concentration leaves at the analytic time
    half = EPHI4 + fraction * AD41 / (1.0 + 0.5 * B4D * C_J) ** 2
    after = t > POLYMER_PV
    assert first_crossing(t[after], c[after], 0.5 * C_J_PPM) - POLYMER_PV == pytest.approx(half, abs=0.005)
    # the wave ends at e + f a: beyond it only the numerical tail remains
    late = (t > POLYMER_PV + EPHI4 + fraction * AD41 + 0.3)
    assert c[late].max() < 0.005 * C_J_PPM


def test_the_grid_refinement_brings_the_desorption_wave_closer():
    errors = []
    tau = np.linspace(EPHI4 + 0.05, EPHI4 + AD41 - 0.15, 25)
    for cells in (100, 400):
        t, c = effluent(flood(1.0, cells))
        errors.append(float(np.max(np.abs(np.interp(POLYMER_PV + tau, t, c) - desorption_wave_ppm(tau, 1.0)))))
    assert errors[1] < 0.4 * errors[0], errors  # first order: x0.25 for 4x the cells


@pytest.mark.parametrize("fraction", [0.0, 0.5, 1.0])
def test_post_flush_returns_the_reversible_polymer(fraction):
    ds = flood(fraction)
    assert ds.attrs["mass_balance_error_polymer"] <= 1e-10
    adsorbed = ds["polymer_adsorbed"].values
    np.testing.assert_allclose(adsorbed[0], PLATEAU_PPM, rtol=1e-10)  # end of the polymer slug: the plateau
    left = (1.0 - fraction) * PLATEAU_PPM
    np.testing.assert_allclose(adsorbed[1], left, rtol=1e-10, atol=1e-12 * PLATEAU_PPM)
    pv = ds["pv"].values
    produced = float(np.sum(ds["c_polymer_out"].values[1:] * np.diff(pv)))  # ppm x PV
    injected = C_J_PPM * POLYMER_PV
    assert produced == pytest.approx(injected - left, rel=1e-10)


def test_effect_strength_blends_the_adsorption_parameter():
    """f = ADSREV4 + s (1 - ADSREV4): ADSREV4 = 0.5 with s = 0.5 is ADSREV4 = 0.75 with s = 0, exactly."""
    a = simulate(SCHEDULE, {**PARAMS, "ADSREV4": 0.5}, cells=40, pv_step=0.05,
                 effects={**EFFECTS, "reversible_polymer_adsorption": 0.5})
    b = simulate(SCHEDULE, {**PARAMS, "ADSREV4": 0.75}, cells=40, pv_step=0.05, effects=EFFECTS)
    for name in a.data_vars:
        assert np.array_equal(a[name].values, b[name].values), name
    c = simulate(SCHEDULE, PARAMS, cells=40, pv_step=0.05, effects=EFFECTS)
    assert not np.array_equal(a["c_polymer_out"].values, c["c_polymer_out"].values)


def test_kinetic_reversible_adsorption_also_desorbs_everything():
    ds = simulate(SCHEDULE, PARAMS, cells=60, pv_step=0.01, profiles_at=[POLYMER_PV + POSTFLUSH_PV],
                  effects={**EFFECTS, "reversible_polymer_adsorption": 1.0, "kinetic_adsorption": 1.0})
    assert ds.attrs["mass_balance_error_polymer"] <= 1e-10
    assert ds["polymer_adsorbed"].values.max() < 1e-6 * PLATEAU_PPM
