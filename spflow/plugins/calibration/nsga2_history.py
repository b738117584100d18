"""Per-generation record of the NSGA-II history match and Algorithm 3's cross-validation checkpoints (a pymoo callback).

After every generation (pymoo calls the callback once the survivors are chosen; generation 1 is the random initial
population) :class:`CalibrationHistory` stores

* the size of the current Pareto front (rank-0 individuals) and its hypervolume. Objectives of different units and
  magnitudes are divided by the maxima of the *initial population* before the hypervolume (pymoo's ``HV`` indicator)
  is taken with reference point 1.1 in every objective, so values are comparable across generations (Fig. 3.10's
  "front shifts towards the origin" becomes a growing number);
* the best value of each objective on the front;
* the whole front (designs and objectives) at the requested snapshot generations and at the last one (Fig. 3.10);
* every ``n_cross`` generations and at the last generation: the held-out misfits of the front's points from the
  simulator (:class:`~spflow.plugins.calibration.nsga2_heldout.HeldOutCheck`) and σ_loss, their mean. When
  σ_loss < ``sigma_tol`` the run stops there (Algorithm 3, line 16: "end if N_gen^end reached");
* the archive of every design the GA evaluated: pymoo's ``algorithm.off`` when the callback runs, which in
  generation 1 is the random initial population and later the generation's offspring, so the archive holds
  ``pop_size + (generations - 1) * pop_size`` points (each generation's offspring are ``pop_size`` new candidates,
  :mod:`~spflow.plugins.calibration.nsga2_algorithm`). The noise-consistent ranges are built from it
  (:mod:`~spflow.plugins.calibration.nsga2_confidence`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from pymoo.core.callback import Callback
from pymoo.indicators.hv import HV

__all__ = ["CalibrationHistory", "HV_REFERENCE"]

#: Reference point of the normalised hypervolume (objectives divided by the initial population's maxima).
HV_REFERENCE = 1.1


class CalibrationHistory(Callback):
    """Records the run (see module docstring); ``heldout(points) -> misfits (n, n_experiment, n_variable)``;
    ``progress(generation, generations)`` (e.g. ``ctx.report_progress``) is told each finished generation."""

    def __init__(self, generations: int, n_cross: int, sigma_tol: float, snapshots: list[int],
                 heldout: Callable[[np.ndarray], np.ndarray],
                 progress: Callable[[int, int], None] = lambda generation, generations: None):
        super().__init__()
        self.progress = progress
        self.generations, self.n_cross, self.sigma_tol = generations, n_cross, sigma_tol
        self.snapshots = set(snapshots)
        self.heldout = heldout
        self.scale: np.ndarray | None = None
        self.n_front: list[int] = []
        self.hypervolume: list[float] = []
        self.best: list[np.ndarray] = []
        self.fronts: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self.checkpoints: dict[int, np.ndarray] = {}
        self._evaluated: list[np.ndarray] = []
        self.stop_reason = f"reached the maximum of {generations} generations"

    @property
    def last_generation(self) -> int:
        return len(self.n_front)

    @property
    def archive(self) -> np.ndarray:
        """Every evaluated design, generation by generation, shape (n_evaluated, n_param)."""
        return np.concatenate(self._evaluated)

    def notify(self, algorithm) -> None:
        generation = algorithm.n_gen
        X, F = algorithm.opt.get("X", "F")
        self._evaluated.append(algorithm.off.get("X").copy())
        if self.scale is None:
            scale = algorithm.pop.get("F").max(axis=0)
            self.scale = np.where(scale > 0, scale, 1.0)
        self.n_front.append(len(F))
        self.hypervolume.append(float(HV(ref_point=np.full(F.shape[1], HV_REFERENCE))(F / self.scale)))
        self.best.append(F.min(axis=0))
        last = generation >= self.generations
        if generation % self.n_cross == 0 or last:
            misfit = self.heldout(X)
            self.checkpoints[generation] = misfit
            sigma = float(misfit.mean())
            if sigma < self.sigma_tol:
                self.stop_reason = (f"sigma_loss = {sigma:.4g} < sigma_tol = {self.sigma_tol:g} "
                                    f"at generation {generation}")
                algorithm.termination.terminate()
                algorithm.termination.update(algorithm)  # pymoo updated it before this callback: take effect now
                last = True
        if generation in self.snapshots or last:
            self.fronts[generation] = (X.copy(), F.copy())
        self.progress(generation, self.generations)
