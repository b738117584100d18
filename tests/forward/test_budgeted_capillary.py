"""The budgeted mode (``capillary="budgeted"``, the default): the explicit scheme, bit for bit, in every run that
finishes within ``BUDGET_EXPLICIT_SHARE`` of its step budget; past that share, the budget step -- the remaining PV
in ``BUDGET_IMPLICIT_SHARE`` of the remaining steps -- bounds the two stiff terms: the capillary flux takes the
adaptive rule (implicit capillary step) where the explicit diffusion limit is shorter, and waves faster than the
budget step allows of a phase near its residual take the implicit release (``transport.implicit_release_fluxes``).

References are computed here: the explicit mode run in the same test -- an independent path only while the budgeted
run did not switch, so every identity test also asserts that it did not -- the outputs' own balances (profiles plus
effluent integrals, never the kernel's bookkeeping alone), the injected schedule, and the explicit run at a tenth of
the Courant number for the accuracy of a switched run.
"""

import json
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest

from spflow.core.stage import StageContext
from spflow.plugins.forward import state_layout as L
from spflow.plugins.forward import transport as T
from spflow.plugins.forward.budgets import STEP_BUDGET_FACTOR, expected_steps
from spflow.plugins.forward.errors import SimulationError
from spflow.plugins.forward.kernel import BUDGET_EXPLICIT_SHARE, BUDGET_IMPLICIT_SHARE
from spflow.plugins.forward.schedule import BCF_SCHEDULES
from spflow.plugins.forward.simulate import simulate
from spflow.plugins.forward.stage import Forward

BALANCE_TOL = 1e-10
COMPONENTS = ("water", "oil", "surfactant", "polymer", "anions", "divalent")
PV = 1.5
WATERFLOOD = [{"pv": PV, "salinity_ppm": 9400.0}]  # the initial-brine salinity: a pure waterflood
PC_ON = {"capillary_desaturation": 0.0, "dispersion": 0.0, "capillary_pressure": 1.0}
LOW_RATE = {"QINJ": 0.0025}  # ml/min: 1/100 of the default rate, capillary dominated


def assert_identical(a, b):
    assert a.attrs["n_steps"] == b.attrs["n_steps"]
    for var in a.data_vars:
        np.testing.assert_array_equal(a[var].values, b[var].values, err_msg=var)


def assert_conserved_and_in_bounds(ds):
    """Every component balanced by the kernel's totals, oil balanced from the outputs (profile plus produced) and
    from the initial oil in place, saturations in [0, 1] summing to 1, non-negative concentrations, oil cut and
    recovery in [0, 1], recovery non-decreasing."""
    for comp in COMPONENTS:
        assert ds.attrs[f"mass_balance_error_{comp}"] <= BALANCE_TOL, comp
    dpv = np.diff(ds.pv.values)
    oil_out = np.cumsum(ds.oil_cut.values[1:] * dpv)
    for t in ds.profile_pv.values:
        k = int(np.argmin(abs(ds.pv.values - t)))
        prof = ds.sel(profile_pv=t)
        # effluent rates are step averages over the output intervals: their integral is exact
        assert abs(prof.oil_overall.mean().item() + oil_out[k - 1] - (1.0 - ds.attrs["param_SWI"])) <= BALANCE_TOL
    sat = ds[["sw", "so", "sme"]].to_array().values
    assert np.all(sat >= 0.0) and np.all(sat <= 1.0 + 1e-12)
    assert np.allclose(sat.sum(axis=0), 1.0, atol=1e-12)
    for var in ("c_polymer", "c_surfactant", "salinity", "c_polymer_out", "c_surfactant_out", "salinity_out"):
        assert np.all(ds[var].values >= 0.0), var
    for var in ("oil_cut", "recovery"):
        assert np.all((ds[var].values >= 0.0) & (ds[var].values <= 1.0)), var
    assert np.all(np.diff(ds.recovery.values) >= 0.0)


def assert_no_switch(ds):
    assert np.isnan(ds.attrs["capillary_implicit_from_pv"])
    assert ds.attrs["capillary_switch"].startswith("none")
    assert ds.attrs["n_capillary_implicit"] == 0
    assert ds.attrs["n_oil_release_implicit"] == 0 and np.isnan(ds.attrs["oil_release_implicit_from_pv"])
    assert ds.attrs["n_non_oleic_release_implicit"] == 0


@pytest.mark.parametrize("schedule", ["BCF1", "BCF2", "BCF3"])
def test_default_runs_are_the_explicit_runs(schedule):
    """BCF1-3 at the defaults (100 cells, Pc off): the default mode is budgeted, it does not switch, and the runs are
    bit-identical to the explicit mode's."""
    a = simulate(schedule, pv_step=0.1, profiles_at=[1.0, 2.0])
    b = simulate(schedule, pv_step=0.1, profiles_at=[1.0, 2.0], capillary="explicit")
    assert a.attrs["capillary"] == "budgeted"
    assert_no_switch(a)
    assert a.attrs["capillary_switch"] == "none: capillary pressure is off"
    assert_identical(a, b)


@pytest.mark.parametrize("schedule, cells", [("BCF1", 30), ("BCF3", 60)])
def test_capillary_runs_inside_half_the_budget_are_the_explicit_runs(schedule, cells):
    """BCF runs with Pc at strength 1 whose explicit step is set by the diffusion limit in many steps but which
    finish within half their budget: no switch, bit-identical to the explicit mode."""
    kwargs = dict(cells=cells, pv_step=0.1, effects={"capillary_pressure": 1.0}, profiles_at=[2.0])
    a = simulate(schedule, **kwargs)
    b = simulate(schedule, capillary="explicit", **kwargs)
    # the explicit run is inside the share of the budget, and its capillary term matters
    budget = STEP_BUDGET_FACTOR * expected_steps(BCF_SCHEDULES[schedule].total_pv, cells, 0.5)
    assert a.attrs["max_steps"] == budget
    assert b.attrs["n_steps"] < BUDGET_EXPLICIT_SHARE * budget
    assert b.attrs["n_capillary_limited"] > 0.1 * b.attrs["n_steps"]
    assert_no_switch(a)
    assert_identical(a, b)


@lru_cache(maxsize=None)
def tight_budget_run(max_steps):
    return simulate("BCF1", cells=30, pv_step=0.05, effects={"capillary_pressure": 1.0}, max_steps=max_steps,
                    profiles_at=[1.0, 2.0, BCF_SCHEDULES["BCF1"].total_pv])


def test_a_run_the_explicit_flux_cannot_finish_in_its_budget_switches_and_finishes():
    """BCF1 with Pc on 30 cells and a budget of 1200 steps (the explicit flux needs about 1 900): the explicit mode
    stops with the budget error; the budgeted mode switches at step 600 (half the budget), records where and why,
    and finishes inside the budget, identical to the explicit run before the switch."""
    max_steps = 1200
    with pytest.raises(SimulationError, match="step budget exhausted"):
        simulate("BCF1", cells=30, pv_step=0.05, effects={"capillary_pressure": 1.0}, max_steps=max_steps,
                 capillary="explicit")
    ds = tight_budget_run(max_steps)
    switch_pv = ds.attrs["capillary_implicit_from_pv"]
    assert 0.0 < switch_pv < BCF_SCHEDULES["BCF1"].total_pv
    assert f"step {int(BUDGET_EXPLICIT_SHARE * max_steps)} of max_steps = {max_steps}" in ds.attrs["capillary_switch"]
    assert 0 < ds.attrs["n_capillary_implicit"] <= ds.attrs["n_steps"] - BUDGET_EXPLICIT_SHARE * max_steps
    assert ds.attrs["n_steps"] <= max_steps
    # before the switch the run is the explicit one (a run with the default budget, which does not stop there)
    ref = simulate("BCF1", cells=30, pv_step=0.05, effects={"capillary_pressure": 1.0}, capillary="explicit")
    before = ds.pv.values < switch_pv
    assert before.sum() >= 5
    for var in ("dp", "oil_cut", "recovery", "c_polymer_out", "c_surfactant_out", "salinity_out"):
        np.testing.assert_array_equal(ds[var].values[before], ref[var].values[before], err_msg=var)
    # ... and not after it (the switch did change the run)
    assert np.max(np.abs(ds.recovery.values - ref.recovery.values)) > 0.0


def test_a_switched_run_conserves_mass_and_stays_in_bounds():
    """The switched run of the previous test conserves every component and keeps every output in its bounds."""
    assert_conserved_and_in_bounds(tight_budget_run(1200))


@lru_cache(maxsize=None)
def waterflood(capillary, cfl=0.5, max_steps=None):
    return simulate(WATERFLOOD, LOW_RATE, cells=25, effects=PC_ON, capillary=capillary, cfl=cfl, pv_step=0.05,
                    max_steps=max_steps)


def test_a_capillary_dominated_flood_finishes_in_the_default_budget_near_the_converged_explicit_run():
    """A low-rate waterflood whose explicit diffusion limit needs ~65 000 steps against a default budget of 15 000:
    the explicit mode stops with the budget error; the budgeted mode switches at half the budget, takes the
    implicit step at the switch step ``remaining PV / (BUDGET_IMPLICIT_SHARE x remaining steps)`` (so at most that
    share of the remaining steps), finishes inside the budget, and its recovery is within 2e-3 (dp within 1 % from 0.15 PV on) of the explicit run at cfl 0.1."""
    budget = STEP_BUDGET_FACTOR * expected_steps(PV, 25, 0.5)
    with pytest.raises(SimulationError, match=f"max_steps = {budget}"):
        waterflood("explicit")
    ds = waterflood("budgeted")
    assert ds.attrs["max_steps"] == budget and ds.attrs["n_steps"] <= budget
    switch_at = int(BUDGET_EXPLICIT_SHARE * budget)
    assert f"at step {switch_at} of max_steps = {budget}" in ds.attrs["capillary_switch"]
    assert 0.0 < ds.attrs["capillary_implicit_from_pv"] < PV
    # the capillary-limited implicit steps take at most BUDGET_IMPLICIT_SHARE of the steps left at the switch
    assert 0 < ds.attrs["n_capillary_implicit"] <= BUDGET_IMPLICIT_SHARE * (budget - switch_at) + 1
    ref = waterflood("explicit", 0.1, 10**8)
    assert np.max(np.abs(ds.recovery.values - ref.recovery.values)) <= 2e-3
    later = ref.pv.values >= 0.15
    assert np.max(np.abs(ds.dp.values[later] / ref.dp.values[later] - 1.0)) <= 0.01
    for comp in COMPONENTS:
        assert ds.attrs[f"mass_balance_error_{comp}"] <= BALANCE_TOL, comp


def test_the_forward_stage_records_the_switch_per_sample_and_experiment():
    """The stage's default is the budgeted mode; its ``capillary_implicit_from_pv`` is each run's attr (the switched
    waterflood: finite; BCF1 without Pc: NaN); the explicit mode's waterflood is a failed sample."""
    experiments = [{"name": "WF", "schedule": WATERFLOOD, "params": LOW_RATE}, "BCF1"]
    stage = Forward(experiments=experiments, cells=25, effects=PC_ON, pv_step=0.05)
    assert stage.params["capillary"] == "budgeted"
    out = stage.run(StageContext("forward", verbose=False))
    direct = waterflood("budgeted")
    assert out["capillary_implicit_from_pv"].values[0, 0] == direct.attrs["capillary_implicit_from_pv"]
    # the waterflood's grid is the first points of the stage's common grid (0 to 1.5 PV of 0 to 4.23)
    np.testing.assert_array_equal(out["recovery"].values[0, 0, :direct.pv.size], direct.recovery.values)
    bcf1 = simulate("BCF1", cells=25, effects=PC_ON, pv_step=0.05)
    assert np.isnan(bcf1.attrs["capillary_implicit_from_pv"]) == np.isnan(out["capillary_implicit_from_pv"].values[0, 1])
    with pytest.warns(UserWarning, match="1 of 1 samples failed"):
        failed = Forward(experiments=experiments, cells=25, effects=PC_ON, pv_step=0.05,
                         capillary="explicit").run(StageContext("forward", verbose=False))
    assert "step budget exhausted" in str(failed["failure"].values[0])
    assert np.isnan(failed["capillary_implicit_from_pv"].values[0, 0])
    assert np.isnan(out["oil_release_implicit_from_pv"].values).all()  # neither run needed the release


def test_two_d_runs_accept_the_default_and_reject_the_other_modes():
    from spflow.core.errors import ParameterError

    with pytest.raises(ParameterError, match="capillary = 'adaptive' is available in 1-D runs only"):
        simulate("BCF1", cells=(6, 3), capillary="adaptive")


def test_the_release_sweep_is_the_linearised_backward_euler_upwind_update():
    """``implicit_release_fluxes`` on three hand-made water/oil cells: the two with an oleic Courant number above the
    limit get the outflow ``F = (f + lam c F_in) / (1 + lam c)`` (hand values; the injector brings no oil, the
    second cell's inflow is the first one's released fraction), water the rest, polymer and salts in the water;
    the third cell's face and the injector face are untouched."""
    n, lam, cfl = 3, 0.1, 0.5
    pr = np.zeros((L.NPR, n))
    f_o = np.array([0.1, 0.05, 0.2])
    pr[L.F1 + 1] = f_o
    pr[L.F1] = 1.0 - f_o
    pr[L.C1P] = 1.0  # aqueous phase: water
    pr[L.C2P + 1] = 1.0  # oleic phase: oil
    pr[L.PCX] = 1.0
    pr[L.CP] = 0.5
    pr[L.C5] = 0.1
    pr[L.C6] = 0.01
    pr[L.WAVE_R] = [100.0, 100.0, 0.1]  # lam c = 10, 10, 0.01
    pr[L.REL] = 1.0  # the oleic phase
    out = np.full((T.NFLUX, n + 1), 7.0)
    count, count_non_oleic, fc_out = T.implicit_release_fluxes(pr, n, lam, cfl, out)
    assert count == 2 and count_non_oleic == 0 and fc_out == -1.0
    big_f0 = (0.1 + 10.0 * 0.0) / 11.0
    big_f1 = (0.05 + 10.0 * big_f0) / 11.0
    for j, big in ((1, big_f0), (2, big_f1)):
        assert out[T.FO, j] == pytest.approx(big, rel=1e-14)
        assert out[T.FW, j] == pytest.approx(1.0 - big, rel=1e-14)
        assert out[T.FP, j] == pytest.approx(0.5 * (1.0 - big), rel=1e-14)
        assert out[T.FA, j] == pytest.approx(0.1 * (1.0 - big), rel=1e-14)
        assert out[T.FD, j] == pytest.approx(0.01 * (1.0 - big), rel=1e-14)
        assert out[T.FS, j] == 0.0
    assert np.all(out[:, 0] == 7.0) and np.all(out[:, 3] == 7.0)


def test_the_release_sweep_of_an_aqueous_or_microemulsion_phase():
    """``implicit_release_fluxes`` on four hand-made three-phase cells (aqueous: water; oleic: oil; microemulsion:
    half water, 0.3 oil, 0.2 surfactant) whose release phase is not the oleic one: cell 0 releases its aqueous phase
    (the injector brings no oil, so its inflow is the cell's aqueous share of the non-oleic flow, 0.3 / 0.9), cell 1
    its microemulsion (inflow: cell 0's released microemulsion fraction), cell 2 is below the limit (its outflow face
    first-order upwind), cell 3 releases its aqueous phase (inflow: cell 2's aqueous fraction) and is the outlet
    (the carrier fraction returned). Hand values: ``F = (f + lam c F_in) / (1 + lam c)``, the other two phases
    scaled by ``(1 - F) / (1 - f)``, every component with the phase compositions."""
    n, lam, cfl = 4, 0.1, 0.5
    f = np.array([[0.3, 0.1, 0.6], [0.5, 0.2, 0.3], [0.4, 0.1, 0.5], [0.2, 0.3, 0.5]])  # cells x phases
    pr = np.zeros((L.NPR, n))
    for l in range(3):
        pr[L.F1 + l] = f[:, l]
    pr[L.C1P] = 1.0
    pr[L.C2P + 1] = 1.0
    pr[L.C1P + 2], pr[L.C2P + 2], pr[L.C3P + 2] = 0.5, 0.3, 0.2
    pr[L.PCX] = 1.0  # polymer in the aqueous phase
    pr[L.CP] = 0.5
    pr[L.C5] = 0.1
    pr[L.REL] = [0.0, 2.0, 0.0, 0.0]
    pr[L.WAVE_R] = [100.0, 100.0, 0.1, 50.0]  # lam c = 10, 10, 0.01, 5
    out = np.full((T.NFLUX, n + 1), 7.0)
    count, count_non_oleic, fc_out = T.implicit_release_fluxes(pr, n, lam, cfl, out)

    def released(i, l, f_in, lc):
        big = (f[i, l] + lc * f_in) / (1.0 + lc)
        phases = f[i] * (1.0 - big) / (1.0 - f[i, l])
        phases[l] = big
        return phases

    face1 = released(0, 0, 0.3 / 0.9, 10.0)
    face2 = released(1, 2, face1[2], 10.0)
    face3 = f[2]  # cell 2's own fractions, first order
    face4 = released(3, 0, f[2, 0], 5.0)
    assert count == 3 and count_non_oleic == 3 and fc_out == pytest.approx(face4[0], rel=1e-14)
    for j, (a, o, m) in ((1, face1), (2, face2), (3, face3), (4, face4)):
        water = a + 0.5 * m
        assert out[T.FW, j] == pytest.approx(water, rel=1e-14)
        assert out[T.FO, j] == pytest.approx(o + 0.3 * m, rel=1e-14)
        assert out[T.FS, j] == pytest.approx(0.2 * m, rel=1e-14)
        assert out[T.FP, j] == pytest.approx(0.5 * a, rel=1e-14)
        assert out[T.FA, j] == pytest.approx(0.1 * water, rel=1e-14)
        assert out[T.FW, j] + out[T.FO, j] + out[T.FS, j] == pytest.approx(1.0, rel=1e-14)
    assert np.all(out[:, 0] == 7.0)


def fractional_flow_jacobian(sat, coef, expo, h=1e-30):
    """Complex-step derivatives (exact to round-off) of ``f_k = lambda_k / sum(lambda)`` in each saturation (held
    independent, as the wave-speed bound does), Corey mobilities ``lambda_l = coef_l S_l^n_l``."""
    jac = np.zeros((3, 3))
    for j in range(3):
        if sat[j] == 0.0:
            continue
        s = sat.astype(complex)
        s[j] += 1j * h
        lam = coef * s**expo
        jac[:, j] = (lam / lam.sum()).imag / h
    return jac


@pytest.mark.parametrize("sat, coef, fast", [((1e-3, 0.3, 0.699), (1000.0, 80.0, 10.0), 0),
                                             ((0.6, 2e-4, 0.3998), (10.0, 1e5, 10.0), 1),
                                             ((0.2, 0.3, 0.5), (1.0, 2.0, 300.0), 2)])
def test_the_release_phase_and_the_bound_without_its_column(sat, coef, fast):
    """``cell_properties.release_terms`` on three-phase states whose fast phase (largest analytic ``dlambda/dS``)
    is the aqueous phase a hair above zero mobility, then the oleic one, then the microemulsion: that phase, its
    term the given row sum, and the remaining bound the largest row sum of |df_k/dS_j| less its entry in that
    column -- the Jacobian by complex-step differentiation of ``f = lambda / sum(lambda)``."""
    from spflow.plugins.forward.cell_properties import release_terms

    sat = np.array(sat)
    coef = np.array(coef)
    expo = np.array([1.2, 1.05, 3.0])
    lam = coef * sat**expo
    dl = expo * coef * sat**(expo - 1.0)
    f = lam / lam.sum()
    jac = fractional_flow_jacobian(sat, coef, expo)
    rows = np.abs(jac).sum(axis=1)
    rel, wave_r, speed_x = release_terms(*sat, *dl, lam.sum(), *f, *rows)
    expected = int(np.argmax(dl))
    assert rel == expected == fast
    assert wave_r == rows[expected]
    assert speed_x == pytest.approx(np.max(rows - np.abs(jac[:, expected])), rel=1e-9)


def test_a_two_phase_release_leaves_only_the_phase_velocities():
    """Two phases present: the release phase is the present one with the larger ``dlambda/dS`` (an absent phase's
    derivative, however large, does not count) and no derivative term remains (the other phase's is the same
    derivative on ``S_k + S_l = 1``)."""
    from spflow.plugins.forward.cell_properties import release_terms

    rel, wave_r, speed_x = release_terms(0.5, 0.0, 0.5, 2.0, 9.0, 3.0, 4.0, 0.4, 0.0, 0.6, 7.0, 0.0, 7.0)
    assert (rel, wave_r, speed_x) == (2, 7.0, 0.0)


def test_a_run_past_half_its_budget_releases_oil_implicitly_and_finishes():
    """BCF1 on 30 cells with a budget of 500 steps (the explicit scheme needs about 600): the explicit mode stops
    with the budget error; the budgeted mode, past half its budget, takes the waves above the budget step's speed
    with the implicit release -- of oil, and of the aqueous or microemulsion phase where its mobility derivative is
    the largest, microemulsion present -- and finishes inside the budget -- identical to the explicit run before its
    first release, all six components balanced to 1e-10, oil from the outputs, in bounds, and within 0.02 in
    recovery (0.01 at the end) of the explicit run with the default budget (first-order implicit steps, on average
    1.5 x the explicit ones, over the last 60 % of the flood)."""
    kwargs = dict(cells=30, pv_step=0.05, profiles_at=[1.0, 2.0, BCF_SCHEDULES["BCF1"].total_pv])
    with pytest.raises(SimulationError, match="max_steps = 500"):
        simulate("BCF1", capillary="explicit", max_steps=500, **kwargs)
    ds = simulate("BCF1", max_steps=500, **kwargs)
    ref = simulate("BCF1", capillary="explicit", **kwargs)
    assert ds.attrs["n_steps"] <= 500 and ds.attrs["n_halvings"] == 0
    first = ds.attrs["oil_release_implicit_from_pv"]
    assert ds.attrs["n_oil_release_implicit"] > 0 and 0.0 < first < BCF_SCHEDULES["BCF1"].total_pv
    assert ds.attrs["n_non_oleic_release_implicit"] > 0
    assert np.any(ds.sme.sel(profile_pv=2.0).values > 0.0)  # released from 1.6 PV: a microemulsion at 2 PV
    before = ds.pv.values < first
    assert before.sum() >= 5
    for var in ("dp", "oil_cut", "recovery", "c_polymer_out", "c_surfactant_out", "salinity_out"):
        np.testing.assert_array_equal(ds[var].values[before], ref[var].values[before], err_msg=var)
    assert np.max(np.abs(ds.recovery.values - ref.recovery.values)) <= 0.02
    assert abs(ds.recovery.values[-1] - ref.recovery.values[-1]) <= 0.01
    assert_conserved_and_in_bounds(ds)


STRESS_DRAWS = json.loads((Path(__file__).parent / "stress_draws_non_oleic.json").read_text())["draws"]


@pytest.mark.parametrize("draw, kind", [("2244", "non_oleic"), ("2722", "oil"), ("6874", "non_oleic")])
def test_the_stress_draws_with_fast_non_oleic_waves_finish_inside_the_default_budget(draw, kind):
    """The three in-bounds stress draws that the oleic release alone left beyond the default step budget (the
    10 000-draw run; docs/forward_model.md): 2244 and 6874 have the aqueous phase a hair above its residual (three
    phases, and aqueous/microemulsion without oil) and need its release; 2722 has oil a hair above its residual,
    released, whose column of the wave-speed bound the aqueous term kept. With the default budget each finishes, all six
    components balanced to 1e-10, saturations in [0, 1] summing to 1, oil cut and recovery in [0, 1]."""
    case = STRESS_DRAWS[draw]
    ds = simulate(case["schedule"], case["params"], cells=case["cells"], effects=case["effects"], pv_step=0.01,
                  profiles_at=[BCF_SCHEDULES[case["schedule"]].total_pv])
    assert ds.attrs["n_steps"] <= ds.attrs["max_steps"]
    assert ds.attrs[f"n_{kind}_release_implicit"] > 0
    for comp in COMPONENTS:
        assert ds.attrs[f"mass_balance_error_{comp}"] <= BALANCE_TOL, comp
    sat = ds[["sw", "so", "sme"]].to_array().values
    assert np.all(sat >= 0.0) and np.all(sat <= 1.0 + 1e-12)
    assert np.allclose(sat.sum(axis=0), 1.0, atol=1e-12)
    for var in ("oil_cut", "recovery"):
        assert np.all((ds[var].values >= -1e-12) & (ds[var].values <= 1.0 + 1e-12)), var
