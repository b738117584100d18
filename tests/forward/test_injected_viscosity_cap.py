"""The physical cap on the viscosity of a run's injected fluids (issue 22: the over-budget draws were absurd fluids).

The references are Eqs. 2.1-2.3 and 2.11 evaluated by hand here: ``mu_p0 = VIS1 (1 + (AP1 Cp + AP2 Cp^2 + AP3
Cp^3) C_SEP^SSLOPE)`` with ``Cp`` in wt % (ppm / 1e4), ``C_SEP = C51 + (BETAP - 1) C61`` floored at CSE1, anions
0.145 meq/ml per 9400 ppm TDS (Table 2.1 brine); a surfactant slug of volume fraction ``C3`` (ppm / 1e6):
``mu = C1 mu_p0 e^(ALPHAV1 C3) + C3 ALPHAV3 e^(ALPHAV4 C1)``, ``C1 = 1 - C3``. Each case puts the cap between two
values of a parameter a hair apart (``1 -/+ 1e-3`` of the value at which the viscosity equals the cap), so the
test fails if the rule evaluates the viscosity at another concentration or salinity, clips, or uses another cap.
"""

import math

import numpy as np
import pytest
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.core.stage import StageContext
from spflow.plugins.forward.injected_viscosity_cap import MAX_INJECTED_VISCOSITY_CP
from spflow.plugins.forward.run_arguments import validate_run
from spflow.plugins.forward.simulate import simulate
from spflow.plugins.forward.stage import Forward

CAP_CP = 1.0e5  # docs/forward_model.md, "Injected-viscosity cap"
ANIONS_PER_PPM = 0.145 / 9400.0  # meq/ml per ppm TDS (Table 2.1 brine)
CP_WT = 0.3  # 3000 ppm
# no AP1/AP2 term, divalent cations weighted like anions (C_SEP = C51), water 1 cP
BASE = {"AP1": 0.0, "AP2": 0.0, "BETAP": 1.0, "VIS1": 1.0, "SSLOPE": -1.0, "CSE1": 1.0e-4}


def ap3_at_cap(csep: float, sslope: float = -1.0, cp_wt: float = CP_WT) -> float:
    """AP3 at which VIS1 (1 + AP3 Cp^3 C_SEP^SSLOPE) = the cap, with VIS1 = 1 cP."""
    return (CAP_CP - 1.0) / (cp_wt**3 * csep**sslope)


def check(schedule, params, effects=None):
    return validate_run(schedule, params, 30, effects, "tvd", 0.1, None, 0.5)


def test_the_cap_is_the_documented_one():
    assert MAX_INJECTED_VISCOSITY_CP == CAP_CP


@pytest.mark.parametrize("salinity_ppm", [9400.0, 17500.0])
def test_cap_at_the_injected_concentration_and_brine_salinity(salinity_ppm):
    """Polymer in a brine as saline as the initial one (C50 = 0.145 meq/ml) or more: the lowest C_SEP of the run is
    the lower of the two (SSLOPE < 0: the most viscous)."""
    schedule = [{"pv": 1.0, "salinity_ppm": salinity_ppm, "polymer_ppm": 3000.0}]
    lowest = min(0.145, salinity_ppm * ANIONS_PER_PPM)
    a = ap3_at_cap(lowest)
    check(schedule, {**BASE, "AP3": a * (1.0 - 1e-3)})
    with pytest.raises(ParameterError) as err:
        check(schedule, {**BASE, "AP3": a * (1.0 + 1e-3)})
    text = str(err.value)
    for name in ("AP1", "AP2", "AP3", "SSLOPE", "CSE1", "BETAP", "VIS1", "100000 cP", "3000 ppm polymer", "slug 0"):
        assert name in text, name
    assert f"C_SEP = {lowest:.3g} meq/ml" in text
    assert f"[0, {CAP_CP - 1.0:.6g}]" in text  # the allowed range of the Flory-Huggins factor (VIS1 = 1 cP)


def test_a_fresher_chase_sets_the_salinity_and_cse1_floors_it():
    """A chase fresher than the polymer slug lowers C_SEP where they mix: the rule takes it; a 0 ppm chase is
    floored at CSE1 (the kernel's max(C_SEP, CSE1))."""
    slug = {"pv": 0.5, "salinity_ppm": 9400.0, "polymer_ppm": 3000.0}
    for chase_ppm, csep in ((940.0, 940.0 * ANIONS_PER_PPM), (0.0, 0.01)):
        schedule = [slug, {"pv": 0.5, "salinity_ppm": chase_ppm}]
        params = {**BASE, "CSE1": 0.01}
        a = ap3_at_cap(csep)
        check(schedule, {**params, "AP3": a * (1.0 - 1e-3)})
        with pytest.raises(ParameterError, match=f"C_SEP = {csep:.3g} meq/ml"):
            check(schedule, {**params, "AP3": a * (1.0 + 1e-3)})
        # the same AP3 passes without the fresh chase: the slug's own brine is 10x (or more) more saline
        check([slug], {**params, "AP3": a * (1.0 + 1e-3)})


def test_positive_sslope_takes_the_most_saline_fluid():
    schedule = [{"pv": 0.5, "salinity_ppm": 9400.0, "polymer_ppm": 10000.0}, {"pv": 0.5, "salinity_ppm": 94000.0}]
    a = ap3_at_cap(94000.0 * ANIONS_PER_PPM, sslope=1.0, cp_wt=1.0)
    check(schedule, {**BASE, "SSLOPE": 1.0, "AP3": a * (1.0 - 1e-3)})
    with pytest.raises(ParameterError, match="C_SEP = 1.45 meq/ml"):
        check(schedule, {**BASE, "SSLOPE": 1.0, "AP3": a * (1.0 + 1e-3)})


def test_polymer_salinity_effect_scales_the_exponent():
    """The kernel's exponent is s x SSLOPE: with s = 0 the salinity factor is 1."""
    schedule = [{"pv": 1.0, "salinity_ppm": 9400.0, "polymer_ppm": 3000.0}]
    params = {**BASE, "AP3": ap3_at_cap(0.145) * 1.01}
    with pytest.raises(ParameterError, match="polymer_salinity strength 1"):
        check(schedule, params)
    # s = 0: mu_p0 = 1 + AP3 Cp^3 = 1 + 1.01 (cap - 1) x 0.145, below the cap
    check(schedule, params, {"polymer_salinity": 0.0})


def test_a_surfactant_slug_is_capped_by_eq_2_11():
    """A 1 % surfactant slug without polymer: ALPHAV3 e^(ALPHAV4 C1) grows as e^20 at ALPHAV4 = 20 (its bound)."""
    c3 = 0.01
    schedule = [{"pv": 1.0, "salinity_ppm": 9400.0, "surfactant_ppm": c3 * 1e6}]
    params = {"VIS1": 1.0, "ALPHAV1": 0.0, "ALPHAV4": 20.0}
    a3 = (CAP_CP - (1.0 - c3)) / (c3 * math.exp(20.0 * (1.0 - c3)))  # ~0.025 cP
    check(schedule, {**params, "ALPHAV3": a3 * (1.0 - 1e-3)})
    with pytest.raises(ParameterError, match=r"ALPHAV1-5 = 0, 2, .*, 20, 0.7"):
        check(schedule, {**params, "ALPHAV3": a3 * (1.0 + 1e-3)})


def test_an_sp_slug_takes_the_polymer_solution_as_the_solvent():
    """With ALPHAV1 = ALPHAV3 = 0, Eq. 2.11 of a 1 % surfactant slug is 0.99 mu_p0: the AP3 at the cap moves by
    1/0.99 against the polymer-only slug."""
    c3 = 0.01
    schedule = [{"pv": 1.0, "salinity_ppm": 9400.0, "polymer_ppm": 3000.0, "surfactant_ppm": c3 * 1e6}]
    params = {**BASE, "ALPHAV1": 0.0, "ALPHAV3": 0.0}
    a = (CAP_CP / (1.0 - c3) - 1.0) / (CP_WT**3 / 0.145)
    check(schedule, {**params, "AP3": a * (1.0 - 1e-3)})
    with pytest.raises(ParameterError, match="polymer, 10000 ppm surfactant"):
        check(schedule, {**params, "AP3": a * (1.0 + 1e-3)})
    assert ap3_at_cap(0.145) < a * (1.0 - 1e-3)  # the same AP3 would be rejected in a polymer-only slug


def test_a_run_without_polymer_is_never_rejected():
    params = {**BASE, "AP3": 1.0e6, "SSLOPE": -5.0, "CSE1": 1.0e-8}
    check([{"pv": 1.0, "salinity_ppm": 0.0}], params)


def test_simulate_and_the_forward_stage_reject_before_any_work():
    schedule = [{"pv": 1.0, "salinity_ppm": 9400.0, "polymer_ppm": 3000.0}]
    bad = {**BASE, "AP3": ap3_at_cap(0.145) * 1.01}
    with pytest.raises(ParameterError, match="above the physical cap"):
        simulate(schedule, bad, cells=10)
    stage = Forward(experiments=[{"name": "poly", "schedule": schedule, "params": {}}], fixed=BASE, cells=10)
    design = xr.Dataset({"values": (("sample", "param"), np.array([[1.0], [bad["AP3"]]]))},
                        coords={"sample": [0, 1], "param": ["AP3"]})
    with pytest.raises(ParameterError, match="above the physical cap"):
        stage.run(StageContext("fwd", verbose=False), design=design)


def test_the_thesis_defaults_pass_with_every_bcf_schedule_and_a_fresh_chase():
    """The calibrated parameters (Table 2.4) give ~47 cP in the BCF1 SP slug; even a 0 ppm chase (C_SEP at CSE1 =
    1e-4 meq/ml) after a 3300 ppm slug stays below the cap: 1 + (15 x 0.33 + 155 x 0.33^3) x 1e-4^-0.76.
    A run without polymer and surfactant is never rejected (test above)."""
    for name in ("BCF1", "BCF2", "BCF3"):
        check(name, {})
    expected = 1.0 + (15.0 * 0.33 + 155.0 * 0.33**3) * 1.0e-4 ** -0.76
    assert expected < CAP_CP
    check([{"pv": 0.5, "salinity_ppm": 9400.0, "polymer_ppm": 3300.0}, {"pv": 0.5, "salinity_ppm": 0.0}], {})
