"""The ``pck`` surrogate kind: PC-Kriging (thesis §3.8, Eq. 3.19; Schöbi, Sudret & Wiart 2015).

The trend candidates come from a sparse PCE: the degree/q-norm-adaptive hybrid-LARS fit of :mod:`.degree_adaptive`
(Algorithm 2's basis search) picks the basis, and hybrid LARS (:mod:`.lars`) on that basis ranks and selects each
output's polynomials. :mod:`.pck_modes` then calibrates universal Kriging on them (``sequential`` or ``optimal``);
the GLS trend coefficients are re-estimated by Kriging, not taken from the PCE.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from . import sobol_from_pce as sobol
from .contract import reference_points
from .degree_adaptive import fit_pce
from .kriging_surrogate import NUGGET, RESTARTS, KrigingSurrogate, output_groups
from .outputs import OutputIndex

__all__ = ["PCK"]


class PCK(KrigingSurrogate):
    """PC-Kriging; build with :meth:`fit` (or the ``pck`` stage)."""

    kind = "pck"
    label = "PC-Kriging"

    @classmethod
    def fit(cls, names: list[str], lower: np.ndarray, upper: np.ndarray, outputs: OutputIndex, x: np.ndarray,
            y: np.ndarray, *, degree_max: int = 3, q: float = 0.9, mode: str = "sequential",
            kernel: str = "gaussian", share: str = "output", nugget: float = NUGGET, restarts: int = RESTARTS,
            seed: int = 0, parallel=None, progress=None, inputs=None) -> PCK:
        """Fit on points ``x`` (N, d) in physical units and outputs ``y`` (N, m); the inputs are uniform on the box
        unless ``inputs`` gives their marginals (:mod:`.input_marginals`): the trend is then a PCE on their
        orthonormal families and the kernel acts on their reference variables."""
        from .basis import design_matrix  # numba and scikit-learn load when a PCK is fitted
        from .lars import hybrid_lars_outputs

        cls.check_options(mode=mode, kernel=kernel, share=share, nugget=nugget, restarts=restarts)
        marginals, x, y = cls.check_training(names, lower, upper, outputs, x, y, inputs)
        output_groups(outputs, share)  # a share="variable" with nothing to share refuses before the trend is fitted
        families = [m.polynomials for m in marginals]
        z = reference_points(marginals, x)
        pce = fit_pce(z, y, degree_max=degree_max, q=q, solver="lars", parallel=parallel, families=families)
        # the trend's candidates: the ranking up to its smallest corrected LOO (the Kriging LOO then chooses among its
        # prefixes, mode "optimal"), not the shorter one-SE model the sparse PCE keeps
        ranked = [r.active for r in hybrid_lars_outputs(design_matrix(z, pce.indices, families), y,
                                                        prefix_rule="min_loo")]
        used = np.unique(np.concatenate(ranked))  # keep only the terms some output's trend can use
        orders = [np.searchsorted(used, r) for r in ranked]
        info = {"pce_degree": pce.degree, "pce_q": pce.q, "pce_loo_mean": pce.loo_mean}
        return cls.fit_trends(names, lower, upper, outputs, x, y, pce.indices[used], orders, mode=mode,
                              kernel=kernel, share=share, nugget=nugget, restarts=restarts, seed=seed,
                              parallel=parallel, info=info, progress=progress, inputs=marginals)

    def sobol(self) -> xr.Dataset:
        """First-order and total Sobol indices of the Kriging *trend* Σ β̂_α Ψ_α (orthonormal under the input marginals,
        :mod:`.sobol_from_pce` applied to the GLS coefficients), dims (output, param). The Gaussian-process part
        σ² Z(ξ) of Eq. 3.19 is not included: these are the indices of the polynomial trend only, equal to those of the
        model when the trend carries the response (a small process variance)."""
        return sobol.sobol_dataset(self.names, self.outputs, self.indices, self.coefficients)
