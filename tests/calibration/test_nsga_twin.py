"""The chapter-3 pipeline on a clean synthetic twin at reduced cost (30 cells, N_s = 60, 40 x 30 GA).

What is asserted is that calibrating on BCF1 through the PCE transfers to the held-out corefloods: the simulator at
the final Pareto set fits BCF2/BCF3 several times better than the prior does. The issue's stricter acceptance
(σ_loss within 1.5x of the truth's own misfit, truth inside every calibrated range) is measured by
scripts/twin_history_matching.py at full cost and is NOT met (docs/calibration.md gives the numbers), so it is not
asserted here.
"""

import runpy
from pathlib import Path

from scipy.stats import qmc

from spflow.core.stage import StageContext
from spflow.plugins.calibration.nsga2_heldout import HeldOutCheck
from spflow.plugins.forward.stage import Forward

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "twin_history_matching.py"


def test_twin_calibration_on_bcf1_transfers_to_the_held_out_corefloods(tmp_path):
    twin = runpy.run_path(str(SCRIPT))
    r = twin["twin_check"](tmp_path, samples=60, degree_max=2, cells=30, population=40, generations=30,
                           profile="thesis")  # BCF1 trains, BCF2/BCF3 are held out
    cal = r["calibration"]
    assert cal.attrs["generations_run"] == 30 and cal["checkpoint"].values.tolist() == [30]
    # the prior's held-out misfit: 16 Latin-hypercube points of the Table 3.2 box, same simulator and data
    names = [str(n) for n in cal["param"].values]
    lo, hi = cal["prior_lower"].values, cal["prior_upper"].values
    prior = qmc.scale(qmc.LatinHypercube(d=len(names), rng=0).random(16), lo, hi)
    check = HeldOutCheck(Forward(experiments=["BCF2", "BCF3"], cells=30), r["observations"], ["recovery", "dp"],
                         names)
    sigma_prior = float(check.misfits(StageContext("prior", verbose=False), prior).mean())
    sigma_final = float(cal["sigma_loss"].sel(checkpoint=30))
    print(f"sigma_loss prior {sigma_prior:.4f}, final Pareto set {sigma_final:.4f}, truth "
          f"{r['truth_misfit'].mean():.4f}; ratio to truth {r['ratio']:.2f}; truth inside "
          f"{sum(r['truth_inside'].values())}/{len(names)} calibrated ranges")
    assert sigma_final < 0.5 * sigma_prior
