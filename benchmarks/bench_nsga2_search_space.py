"""Should NSGA-II search the box or the marginals' quantile space? (issue #24; docs/calibration.md, "Search space")

Two misfits q1 = ½‖x − a‖², q2 = ½‖x − b‖² on the box [0, 1]^4, whose Pareto set is the segment [a, b] (the
triangle inequality: ‖x − a‖ + ‖x − b‖ = ‖a − b‖ on it, larger anywhere else). Every parameter has the prior
TruncatedNormal(0.5, std) on [0, 1], std = 0.15 or 0.08, a lab prior of the ``priors`` stage's kind (its support is
the box). The thesis's
NSGA-II (:func:`spflow.plugins.calibration.nsga2_algorithm.thesis_nsga2`, population 120) runs 50 generations either
on the box (x is the search variable) or on the quantile space (u in [0, 1]^4, x = F⁻¹(u) through each marginal's
quantile function). Three placements of the Pareto set: at the prior's mode, in its tail (0.8-0.9) and at the box's
edge (0.9-0.98). Reported over 5 seeds: the final front's median and largest excess
(‖x − a‖ + ‖x − b‖ − ‖a − b‖)/‖a − b‖ (0 on the Pareto set), and the distance from each end a, b to the nearest front
member (how much of the set the front spans).

    PYTHONPATH=. python benchmarks/bench_nsga2_search_space.py
"""

from __future__ import annotations

import numpy as np

from spflow.plugins.calibration.nsga2_algorithm import thesis_nsga2
from spflow.plugins.surrogates.input_marginals import TruncatedNormal, from_unit_hypercube

D, POPULATION, GENERATIONS, SEEDS, STDS = 4, 120, 50, range(5), (0.15, 0.08)
CASES = {
    "at the mode": (np.array([0.45, 0.55, 0.5, 0.48]), np.array([0.55, 0.45, 0.52, 0.56])),
    "in the tail": (np.array([0.8, 0.85, 0.82, 0.88]), np.array([0.9, 0.8, 0.86, 0.84])),
    "at the edge": (np.array([0.9, 0.95, 0.92, 0.97]), np.array([0.98, 0.9, 0.96, 0.93])),
}


def run(a: np.ndarray, b: np.ndarray, space: str, prior: list, seed: int) -> np.ndarray:
    """The final Pareto designs x (physical) of one run searching ``space`` ("box" or the "quantile" space of the
    marginals ``prior``)."""
    from pymoo.core.problem import Problem
    from pymoo.optimize import minimize

    to_x = (lambda u: from_unit_hypercube(prior, u)) if space == "quantile" else (lambda x: x)

    class Misfits(Problem):
        def __init__(self):
            super().__init__(n_var=D, n_obj=2, xl=np.zeros(D), xu=np.ones(D))

        def _evaluate(self, v, out, *args, **kwargs):
            x = to_x(v)
            out["F"] = np.c_[0.5 * np.sum((x - a) ** 2, axis=1), 0.5 * np.sum((x - b) ** 2, axis=1)]

    result = minimize(Misfits(), thesis_nsga2(pop_size=POPULATION), ("n_gen", GENERATIONS), seed=seed, verbose=False)
    return to_x(np.atleast_2d(result.X))


def main() -> None:
    print(f"NSGA-II (thesis settings, population {POPULATION}, {GENERATIONS} generations), d = {D}; median over seeds "
          f"{list(SEEDS)} (worst in brackets)")
    for std in STDS:
        prior = [TruncatedNormal(0.5, std, 0.0, 1.0)] * D
        print(f"\nprior {prior[0]!r} per parameter")
        print(f"{'Pareto set':<12} {'search':<9} {'median excess':>18} {'max excess':>18} {'gap to a':>18} "
              f"{'gap to b':>18}")
        for case, (a, b) in CASES.items():
            length = np.linalg.norm(b - a)
            for space in ("box", "quantile"):
                rows = []
                for seed in SEEDS:
                    x = run(a, b, space, prior, seed)
                    excess = (np.linalg.norm(x - a, axis=1) + np.linalg.norm(x - b, axis=1) - length) / length
                    rows.append([np.median(excess), excess.max(), np.linalg.norm(x - a, axis=1).min() / length,
                                 np.linalg.norm(x - b, axis=1).min() / length])
                cells = [f"{np.median(c):.2e} [{c.max():.1e}]" for c in np.array(rows).T]
                print(f"{case:<12} {space:<9} " + " ".join(f"{c:>18}" for c in cells))


if __name__ == "__main__":
    main()
