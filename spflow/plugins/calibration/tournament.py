"""Tournament selection of size k for pymoo's NSGA-II: feasibility, then non-domination rank, then crowding distance.

The thesis selects parents by tournament (§3.6.2): ``T_s = 4`` individuals are drawn at random from the population
with probability ``P_s = 1`` and the fittest of them becomes a parent. NSGA-II's notion of "fittest" among
competitors is Deb's crowded-comparison operator: lower non-domination rank wins, a tie in rank goes to the larger
crowding distance (a less crowded part of the front), and a remaining tie is broken at random. pymoo ships this only
for binary tournaments (``pymoo.algorithms.moo.nsga2.binary_tournament`` raises "Only implemented for binary
tournament!" when ``pressure != 2``), so :func:`crowded_tournament` implements the k-way version. It is used as

    TournamentSelection(pressure=4, func_comp=crowded_tournament)

which maps the thesis's ``T_s = 4``, ``P_s = 1`` one to one: pymoo draws ``pressure`` distinct competitors per
tournament (random permutations of the population) and always takes the winner. The rank and crowding distance are
those the rank-and-crowding survival attached to the population (attributes ``rank`` and ``crowding``).
Constraint violation is compared first (smaller wins), as pymoo's binary comparator does, so the comparator remains
correct for constrained problems; for the box-bounded calibration every individual is feasible.

How the other MATLAB-style settings of the thesis map onto pymoo operators is documented in
:mod:`spflow.plugins.calibration.nsga2_algorithm` and docs/calibration.md.
"""

from __future__ import annotations

import numpy as np

from spflow.core.errors import SpflowError

__all__ = ["crowded_tournament"]


def crowded_tournament(pop, P: np.ndarray, random_state: np.random.Generator, **kwargs) -> np.ndarray:
    """Winner of each tournament (row of ``P``, population indices) by crowded comparison; returns (n_tournaments,).

    Lexicographic order per competitor: constraint violation (ascending), rank (ascending), crowding distance
    (descending), then a uniform random key from ``random_state`` (pymoo passes the run's generator) so that exact
    ties are decided at random. Extra keyword arguments pymoo passes (``algorithm``) are not needed.
    """
    P = np.asarray(P, dtype=int)
    if P.ndim != 2 or P.shape[1] < 2:
        raise SpflowError(f"crowded_tournament: expected a (n_tournaments, k >= 2) index matrix, got shape {P.shape}")
    rank, crowding, cv = (np.asarray(v, dtype=float) for v in pop.get("rank", "crowding", "CV"))
    if np.isnan(rank).any() or np.isnan(crowding).any():
        raise SpflowError("crowded_tournament: the population lacks 'rank'/'crowding'; use it with a rank-and-crowding "
                          "survival (NSGA-II) that sets them before mating")
    n, k = P.shape
    cv = np.nan_to_num(cv.reshape(len(pop), -1)[:, 0])
    tie = random_state.random(P.shape)
    row = np.repeat(np.arange(n), k)
    # np.lexsort's last key is the primary one: group by tournament, then cv, rank, -crowding, random tie-break
    order = np.lexsort((tie.ravel(), -crowding[P].ravel(), rank[P].ravel(), cv[P].ravel(), row))
    return P.ravel()[order[::k]]
