"""Shear thinning exported to OPM Flow (PLYSHLOG, :mod:`spflow.export.opm_shear`) against spflow, same cells,
spflow's first-order scheme.

* Single-phase polymer flood with rate steps (a core at residual oil, ``SWI = 1 - S2RWC``, ``S1RWC = 0.2`` so OPM's
  ``S_w - Swcr`` is not ``S_w``): the per-slug rates go into WCONINJE, and the pressure drop at every rate plateau
  (0.0625 to 2 ml/min: equivalent shear rates 25 to 790 1/s around the half shear rate of 60 1/s) agrees
  within 2 %. The mapping is exact here (the saturation cannot change).
* Two-phase polymer flood (the acceptance case of ``test_opm_flow_agreement`` with shear thinning on): the export is
  an approximation matched at ``S_w* = 1 - S2RWC`` (printed); recovery at the end within 0.005, Δp at the end of the
  polymer slug (plateau) and after the chase water within 2 %.

Both cases check that shear thinning is strong there (spflow's plateau well below its Newtonian one), so agreement
is not an accident of a weak effect. Skips only when ``flow`` is not on PATH (CI installs it, ``.ci/run``).
"""

import shutil

import numpy as np
import pytest

from spflow.export.opm_deck import write_opm_deck
from spflow.export.opm_run import run_opm
from spflow.plugins.forward.schedule import Schedule, Slug
from spflow.plugins.forward.simulate import simulate

pytestmark = pytest.mark.skipif(shutil.which("flow") is None,
                                reason="OPM Flow ('flow') is not on PATH: apt-get install libopm-simulators-bin")

EXACT = {"dispersion": 0.0, "capillary_desaturation": 0.0, "polymer_adsorption": 0.0,
         "inaccessible_pore_volume": 0.0, "permeability_reduction": 0.0, "shear_thinning": 1.0}
NEWTONIAN = EXACT | {"shear_thinning": 0.0}
SHEAR = {"GAMMAC": 40.0, "GAMHF": 60.0, "POWN": 1.66, "IGAMHF": 0}

# single phase: water at residual oil; polymer fills the core at the lowest rate, then the rate doubles per slug
RESIDUAL_OIL = SHEAR | {"S1RWC": 0.2, "S2RWC": 0.3, "SWI": 0.7, "P1RWC": 0.5}
FILL_RATE, RATES, PLATEAU_PV = 0.0625, (0.125, 0.25, 0.5, 1.0, 2.0), 0.2
RATE_STEPS = Schedule(
    (Slug("W", 0.2, 9400.0, rate_ml_min=FILL_RATE), Slug("fill", 1.3, 9400.0, 0.0, 2000.0, rate_ml_min=FILL_RATE))
    + tuple(Slug(f"q{q:g}", PLATEAU_PV, 9400.0, 0.0, 2000.0, rate_ml_min=q) for q in RATES), "rate-steps")
RATE_CELLS, RATE_STEP = 50, 0.05

# two phase: the acceptance schedule of test_opm_flow_agreement
TWO_PHASE = Schedule((Slug("W", 0.5, 9400.0), Slug("P", 1.0, 9400.0, 0.0, 1000.0), Slug("EWF", 1.0, 9400.0)),
                     "polymer-shear")
TWO_CELLS, TWO_STEP = 50, 0.02


def _opm_at(opm, x):
    """OPM's report point nearest ``x`` PV and its Δp (OPM rounds step lengths to whole seconds: at 2 ml/min one
    second is 5e-4 PV, and the slugs' rounding adds up)."""
    i = int(np.argmin(np.abs(opm.pv.values - x)))
    assert abs(opm.pv.values[i] - x) < 2e-3
    return float(opm.pv.values[i]), float(opm.dp.values[i])


@pytest.fixture(scope="module")
def rate_steps(tmp_path_factory):
    deck = write_opm_deck(tmp_path_factory.mktemp("rates") / "CORE.DATA", RATE_STEPS, RESIDUAL_OIL, EXACT,
                          cells=RATE_CELLS, pv_step=RATE_STEP, log=lambda m: None)
    opm = run_opm(deck, form="series")
    ref = simulate(RATE_STEPS, RESIDUAL_OIL, cells=RATE_CELLS, effects=EXACT, scheme="upwind", pv_step=RATE_STEP)
    newtonian = simulate(RATE_STEPS, RESIDUAL_OIL, cells=RATE_CELLS, effects=NEWTONIAN, scheme="upwind",
                         pv_step=RATE_STEP)
    return deck, opm, ref, newtonian


def test_rate_steps_dp_plateaus_agree_with_opm(rate_steps):
    deck, opm, ref, newtonian = rate_steps
    assert deck.shear is not None and deck.shear.exact
    ends = np.cumsum([s.pv for s in RATE_STEPS.slugs])
    measured = []
    for slug, end in list(zip(RATE_STEPS.slugs, ends))[1:]:
        pv, dp_opm = _opm_at(opm, end - RATE_STEP)  # late in the plateau, away from the rate switch
        dp_ref = float(np.interp(pv, ref.pv.values, ref.dp.values))
        dp_newt = float(np.interp(pv, newtonian.pv.values, newtonian.dp.values))
        measured.append((slug.rate_ml_min, dp_opm / dp_ref - 1.0, dp_ref / dp_newt))
    print("\nrate (ml/min), OPM/spflow - 1, spflow/Newtonian: "
          + "; ".join(f"{q:g} {d:+.4f} {t:.3f}" for q, d, t in measured))
    for q, diff, thinning in measured:
        assert abs(diff) <= 0.02, f"dp plateau at {q} ml/min: OPM/spflow - 1 = {diff:+.4f}"
    # shear thinning is strong over the steps: the apparent viscosity falls with the rate
    assert measured[-1][2] < 0.3 and measured[0][2] < 0.8


@pytest.fixture(scope="module")
def two_phase(tmp_path_factory):
    notes = []
    deck = write_opm_deck(tmp_path_factory.mktemp("two") / "CORE.DATA", TWO_PHASE, SHEAR, EXACT, cells=TWO_CELLS,
                          pv_step=TWO_STEP, approximate=True, log=notes.append)
    opm = run_opm(deck, form="series")
    ref = simulate(TWO_PHASE, SHEAR, cells=TWO_CELLS, effects=EXACT, scheme="upwind", pv_step=TWO_STEP)
    newtonian = simulate(TWO_PHASE, SHEAR, cells=TWO_CELLS, effects=NEWTONIAN, scheme="upwind", pv_step=TWO_STEP)
    return deck, notes, opm, ref, newtonian


def test_two_phase_shear_thinning_agrees_with_opm(two_phase):
    deck, notes, opm, ref, newtonian = two_phase
    # the saturation approximation is named and printed; nothing else is approximated
    approximations = [n for n in notes if n.startswith("APPROXIMATION")]
    assert len(approximations) == 1 and "shear_thinning_saturation" in approximations[0]
    assert deck.shear.reference_sw == pytest.approx(1.0 - 0.3)
    recovery = abs(float(opm.recovery[-1]) - float(ref.recovery[-1]))
    pv, dp_opm = _opm_at(opm, 1.5)  # end of the polymer slug
    plateau = dp_opm / float(np.interp(pv, ref.pv.values, ref.dp.values)) - 1.0
    thinning = float(np.interp(pv, ref.pv.values, ref.dp.values)) / float(
        np.interp(pv, newtonian.pv.values, newtonian.dp.values))
    pv_end, dp_end = _opm_at(opm, TWO_PHASE.total_pv)
    residual = dp_end / float(np.interp(pv_end, ref.pv.values, ref.dp.values)) - 1.0
    print(f"\ntwo-phase shear: recovery diff {recovery:.2e}, dp plateau OPM/spflow - 1 {plateau:+.4f} "
          f"(spflow/Newtonian {thinning:.3f}), dp end {residual:+.4f}")
    assert recovery <= 0.005
    assert abs(plateau) <= 0.02
    assert abs(residual) <= 0.02
    assert thinning < 0.8
