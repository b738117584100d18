"""Universal Kriging at fixed correlation hyperparameters: GLS trend, process variance, prediction, Dubrule LOO.

The model of thesis Eqs. 3.18-3.19 (Schöbi, Sudret & Wiart 2015): y(z) = f(z)ᵀβ + σ² Z(z), with f a set of orthonormal
polynomials of the inputs' marginals (Legendre for uniform inputs; the PC-Kriging trend; the constant alone gives
ordinary Kriging) and Z a stationary unit-variance Gaussian process with correlation R(z, z'; θ) -- the squared
exponential of Eq. 3.20 or Matérn 5/2. Several output columns may share one correlation matrix (one Cholesky factor)
while each keeps its own trend terms, coefficients and process variance. With R = C(θ) + τI (τ: a small nugget for
conditioning) and F_ij = f_j(z_i), for each column y (Schöbi, Sudret & Wiart 2015; docs/surrogates.md, Closed forms at
fixed hyperparameters):

* β̂ = (FᵀR⁻¹F)⁻¹FᵀR⁻¹y (generalised least squares), σ̂² = (y − Fβ̂)ᵀR⁻¹(y − Fβ̂)/N;
* mean μ(z) = f(z)ᵀβ̂ + r(z)ᵀR⁻¹(y − Fβ̂);
* variance s²(z) = σ̂²[1 − rᵀR⁻¹r + uᵀ(FᵀR⁻¹F)⁻¹u], u = FᵀR⁻¹r − f(z) (the last term is the trend uncertainty);
* leave-one-out residuals with trend re-estimation (Dubrule 1983): e = Qy / diag(Q),
  Q = R⁻¹ − R⁻¹F(FᵀR⁻¹F)⁻¹FᵀR⁻¹; note Qy = R⁻¹(y − Fβ̂).

Everything goes through the Cholesky factor R = LLᵀ and a QR factorisation L⁻¹F = QR, never an explicit inverse of
R or of FᵀR⁻¹F; the triangular inverses L⁻¹ and R⁻¹ are formed once so that prediction is plain matrix products
(scipy's per-call overhead dominated small batches). Factorisations run on one BLAS thread (:mod:`.blas`: these
matrices are small and the callers parallelise one level up).

Correlations (unit variance, ARD length scales ℓ in the [-1, 1] auxiliary space) are GPy's ``RBF`` and ``Matern52``
formulas, exp(−r²/2) and (1 + √5 r + 5r²/3) exp(−√5 r) with r² = Σ_k (Δz_k/ℓ_k)², so Eq. 3.20's θ_k = √2 ℓ_k. They
are evaluated here rather than through ``GPy.kern.*.K``: GPy's slicing and caching wrappers cost ~0.25 ms per call,
which was 60 % of a one-point prediction of a proxy with one Kriging model per output (88 calls). GPy keeps the
hyperparameter fit (kernel gradients, optimiser; :mod:`.kriging_likelihood`), and a test checks both agree.
"""

from __future__ import annotations

import numpy as np

from spflow.core.errors import ParameterError

from .blas import single_threaded_blas
from .regression import is_constant

__all__ = ["KERNELS", "check_kernel", "correlation", "UniversalKriging"]

#: Correlation families (GPy's ``RBF`` = squared exponential, Eq. 3.20; ``Matern52``).
KERNELS = ("gaussian", "matern52")


def check_kernel(name: str, lengthscale: np.ndarray) -> np.ndarray:
    """``lengthscale`` as a float array after checking the kernel name and that the lengths are positive."""
    if name not in KERNELS:
        raise ParameterError(f"Kriging kernel {name!r} is not known; allowed: {sorted(KERNELS)}")
    lengthscale = np.asarray(lengthscale, dtype=float)
    if lengthscale.ndim != 1 or not (np.isfinite(lengthscale).all() and (lengthscale > 0).all()):
        raise ParameterError(f"Kriging length scales must be a 1-D array of positive numbers, got {lengthscale}")
    return lengthscale


def _scaled_sq_distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Σ_k (a_ik − b_jk)² for already ℓ-scaled points (clipped at 0 against round-off)."""
    d2 = np.sum(a**2, axis=1)[:, None] + np.sum(b**2, axis=1)[None, :] - 2.0 * (a @ b.T)
    return np.maximum(d2, 0.0)


def _correlation_of(name: str, d2: np.ndarray) -> np.ndarray:
    if name == "gaussian":
        return np.exp(-0.5 * d2)
    r = np.sqrt(5.0 * d2)
    return (1.0 + r + r**2 / 3.0) * np.exp(-r)


def correlation(name: str, za: np.ndarray, zb: np.ndarray, lengthscale: np.ndarray) -> np.ndarray:
    """Correlation matrix R(za_i, zb_j) (na, nb) of kernel ``name`` with ARD ``lengthscale``."""
    lengthscale = check_kernel(name, lengthscale)
    return _correlation_of(name, _scaled_sq_distance(za / lengthscale, zb / lengthscale))


class UniversalKriging:
    """GLS universal Kriging of the columns of ``y`` sharing one correlation kernel.

    Parameters
    ----------
    z:
        Training inputs (n, d) in the auxiliary space [-1, 1]^d.
    y:
        Training outputs (n, m).
    basis:
        Trend functions at the training inputs (n, P): every column's trend is a subset of them.
    trend:
        Boolean (m, P): ``trend[j, k]`` puts basis function k in column j's trend (at least one per column, and
        fewer than n).
    kernel, lengthscale:
        Correlation family (:data:`KERNELS`) and its length scales (d,).
    nugget:
        τ >= 0 added to the diagonal of the correlation matrix.
    """

    def __init__(self, z: np.ndarray, y: np.ndarray, basis: np.ndarray, trend: np.ndarray, kernel: str,
                 lengthscale: np.ndarray, nugget: float):
        from scipy.linalg import cholesky, qr, solve_triangular  # SciPy's linear algebra loads when a model is fitted

        self.z, self.y, self.basis = z, y, basis
        self.trend = np.asarray(trend, dtype=bool)
        self.kernel, self.lengthscale = kernel, check_kernel(kernel, lengthscale)
        self.nugget = float(nugget)
        self._z_scaled = z / self.lengthscale
        n, m = y.shape
        if self.trend.shape != (m, basis.shape[1]):
            raise ParameterError(f"Kriging trend mask has shape {self.trend.shape}, expected {(m, basis.shape[1])}")
        sizes = self.trend.sum(axis=1)
        if (sizes < 1).any() or (sizes >= n).any():
            raise ParameterError(f"Kriging trend sizes must be in [1, {n - 1}] (fewer terms than the {n} training "
                                 f"points), got {sizes.min()}..{sizes.max()}")
        with single_threaded_blas():  # small factorisations: see .blas
            chol = cholesky(correlation(kernel, z, z, self.lengthscale) + self.nugget * np.eye(n), lower=True)
            self.half_log_det = float(np.sum(np.log(np.diag(chol))))  # ½ log|R|
            self.chol_inv = solve_triangular(chol, np.eye(n), lower=True)  # L⁻¹ (only it is kept)
            self.whitened_basis = self.chol_inv @ basis  # L⁻¹F
            whitened_y = self.chol_inv @ y  # L⁻¹y
            # Columns with the same trend share one QR factor of L⁻¹F_S (for the GP kind: all of them).
            self.sets, set_of_column = np.unique(self.trend, axis=0, return_inverse=True)
            self.set_columns = [np.flatnonzero(set_of_column.ravel() == s) for s in range(len(self.sets))]
            self.q_factors, self.r_inverses = [], []
            self.coefficients = np.zeros((basis.shape[1], m))
            whitened_residual = np.empty_like(whitened_y)
            for mask, cols in zip(self.sets, self.set_columns):
                q, r = qr(self.whitened_basis[:, mask], mode="economic")
                if np.abs(np.diag(r)).min() <= 1e-12 * np.abs(np.diag(r)).max():
                    raise ParameterError(f"Kriging trend: the {mask.sum()} trend functions are linearly dependent at "
                                         "the training points")
                qty = q.T @ whitened_y[:, cols]
                self.coefficients[np.ix_(mask, cols)] = solve_triangular(r, qty)
                whitened_residual[:, cols] = whitened_y[:, cols] - q @ qty
                self.q_factors.append(q)
                self.r_inverses.append(solve_triangular(r, np.eye(r.shape[0])))  # (L⁻¹F_S = QR) R⁻¹
            self.process_variance = np.sum(whitened_residual**2, axis=0) / n  # σ̂²
            self.weights = self.chol_inv.T @ whitened_residual  # R⁻¹(y − Fβ̂)

    def log_likelihood(self) -> float:
        """Concentrated log-likelihood (minus the objective of Eq. 3.21), summed over the columns."""
        n = self.y.shape[0]
        sigma2 = self.process_variance
        return float(-np.sum(self.half_log_det + 0.5 * n * np.log(2 * np.pi * sigma2) + 0.5 * n))

    def log_likelihood_gradient_k(self) -> np.ndarray:
        """d(log-likelihood)/dR (n, n) for GPy's ``update_gradients_full``: ½ Σ_j α_jα_jᵀ/σ̂_j² − (m/2) R⁻¹."""
        alpha, sigma2 = self.weights, self.process_variance
        with single_threaded_blas():
            return 0.5 * (alpha / sigma2) @ alpha.T - 0.5 * sigma2.size * (self.chol_inv.T @ self.chol_inv)

    def predict(self, z: np.ndarray, basis: np.ndarray, variance: bool = True) -> tuple[np.ndarray, np.ndarray | None]:
        """Mean and variance (b, m) at points ``z`` (b, d) whose trend functions are ``basis`` (b, P); with
        ``variance=False`` the variance (an (n, b) triangular product and the trend term) is skipped and None returned.

        Small matrix products: callers that predict many models in a row hold one BLAS thread around them all
        (:func:`.blas.single_threaded_blas`; entering the limit per model cost ~40 µs).
        """
        r = _correlation_of(self.kernel, _scaled_sq_distance(z / self.lengthscale, self._z_scaled))  # (b, n)
        mean = basis @ self.coefficients + r @ self.weights
        if not variance:
            return mean, None
        v = self.chol_inv @ r.T  # L⁻¹r, (n, b)
        reduced = 1.0 - np.sum(v**2, axis=0)  # 1 − rᵀR⁻¹r
        u = self.whitened_basis.T @ v - basis.T  # FᵀR⁻¹r − f, (P, b)
        var = np.empty_like(mean)
        for mask, cols, r_inv in zip(self.sets, self.set_columns, self.r_inverses):
            w = r_inv.T @ u[mask]  # uᵀ(FᵀR⁻¹F)⁻¹u = |R⁻ᵀu|²
            var[:, cols] = np.outer(reduced + np.sum(w**2, axis=0), np.ones(cols.size))
        var *= self.process_variance
        return mean, np.maximum(var, 0.0)

    def loo_residuals(self) -> np.ndarray:
        """Leave-one-out residuals y_i − μ^(−i)(z_i) (n, m) with trend re-estimation (Dubrule 1983)."""
        out = np.empty_like(self.weights)
        with single_threaded_blas():
            diag_r_inv = np.sum(self.chol_inv**2, axis=0)
            for q, cols in zip(self.q_factors, self.set_columns):
                diag_q = diag_r_inv - np.sum((q.T @ self.chol_inv) ** 2, axis=0)
                out[:, cols] = self.weights[:, cols] / diag_q[:, None]
        return out

    def relative_loo(self) -> np.ndarray:
        """ε_LOO per column (Eq. 3.8): Σ e_i² / Σ (y_i − ȳ)²; 0 for a column constant up to round-off
        (:func:`.regression.is_constant`, the PCE's convention)."""
        sse = np.sum(self.loo_residuals() ** 2, axis=0)
        sst = np.sum((self.y - self.y.mean(axis=0)) ** 2, axis=0)
        return np.divide(sse, sst, out=np.zeros_like(sse), where=~is_constant(self.y))
