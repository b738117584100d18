"""The thesis's genetic-algorithm settings (§3.6.2-3.6.3) as a configured pymoo NSGA-II.

The thesis quotes MATLAB-style settings (population 120, tournament size 4, crossover probability 0.8, mutation
probability 0.01; the vocabulary of MATLAB's ``ga``/``gamultiobj``). pymoo's real-coded NSGA-II has different
operators, so each setting is mapped onto the pymoo knob with the same meaning:

* ``pop_size = 120`` (individuals per generation) -> ``NSGA2(pop_size=120)``, 120 offspring per generation.
* ``T_s = 4``, ``P_s = 1`` (the best of 4 random competitors becomes a parent) ->
  ``TournamentSelection(pressure=4, func_comp=crowded_tournament)`` (:mod:`.tournament`).
* ``P_c = 0.8`` ("80 % of the new population is reproduced by crossover", MATLAB's ``CrossoverFraction``) ->
  ``SBX(prob=0.8)``: each mating applies crossover with probability 0.8, otherwise the children are copies of the
  parents, so about 80 % of the offspring are crossover children.
* ``P_m = 0.01`` (each gene of an offspring is altered with probability 0.01; MATLAB's uniform mutation rate is per
  gene) -> ``PM(prob=1.0, prob_var=0.01)``: every offspring enters the mutation operator and each variable mutates
  with probability 0.01.

Notes on the mapping:

* pymoo's ``PM(prob=...)`` is a *per-individual* probability and ``prob_var`` the *per-variable* one (default
  ``min(0.5, 1/n_var)``). The thesis's 0.01 is a gene-level rate, hence ``prob_var=0.01`` with ``prob=1``. With 9
  parameters an offspring is mutated somewhere with probability 1 - 0.99^9 ≈ 8.6 %, much less than pymoo's default
  (about one variable per offspring). The rate is exposed as a parameter.
* The thesis does not say which real-coded crossover MATLAB used (its default for ``gamultiobj`` is
  ``crossoverintermediate``); we use NSGA-II's standard simulated binary crossover with pymoo's default distribution
  index (eta = 15) and polynomial mutation (eta = 20); SBX's per-variable crossover probability stays at pymoo's 0.5.
* Copies of parents that neither crossover nor mutation changed are removed by pymoo's duplicate elimination and
  mating is repeated, so every generation still brings ``pop_size`` new candidates.
* Survival is NSGA-II's elitist rank-and-crowding: the ``combine(P(N), O(N))`` of Algorithm 3, line 11.
"""

from __future__ import annotations


from spflow.plugins.calibration.tournament import crowded_tournament

__all__ = ["thesis_nsga2", "THESIS_GA"]

#: The settings of §3.6.2-3.6.3.
THESIS_GA = {"pop_size": 120, "tournament": 4, "crossover_prob": 0.8, "mutation_prob": 0.01}


def thesis_nsga2(pop_size: int = 120, tournament: int = 4, crossover_prob: float = 0.8, mutation_prob: float = 0.01,
                 crossover_eta: float = 15.0, mutation_eta: float = 20.0):
    """A pymoo NSGA-II with the thesis's selection, crossover and mutation settings (mapping in the module doc)."""
    from pymoo.algorithms.moo.nsga2 import NSGA2  # pymoo loads when an optimisation is built
    from pymoo.operators.crossover.sbx import SBX
    from pymoo.operators.mutation.pm import PM
    from pymoo.operators.selection.tournament import TournamentSelection

    return NSGA2(
        pop_size=pop_size,
        selection=TournamentSelection(pressure=tournament, func_comp=crowded_tournament),
        crossover=SBX(prob=crossover_prob, eta=crossover_eta),
        mutation=PM(prob=1.0, prob_var=mutation_prob, eta=mutation_eta),
        eliminate_duplicates=True,
    )
