"""Univariate orthonormal polynomial families of the Wiener-Askey scheme (Xiu & Karniadakis 2002), the factors of the
PCE basis Ψ_α(ξ) = Π_k φ_{α_k}(ξ_k) of thesis Eq. 3.4.

Each family is orthonormal under a probability measure on its reference variable ξ, E[φ_m(ξ) φ_n(ξ)] = δ_mn,
φ_0 = 1, so the moments and Sobol indices of :mod:`.sobol_from_pce` hold whatever the family (Eqs. 3.11-3.12):

* ``legendre``: ξ ~ U[-1, 1]; φ_n = sqrt(2n+1) P_n, evaluated with Bonnet's recurrence
  (n+1) P_{n+1} = (2n+1) ξ P_n − n P_{n−1};
* ``hermite``: ξ ~ N(0, 1); φ_n = He_n / sqrt(n!) (probabilists' Hermite), He_{n+1} = ξ He_n − n He_{n−1};
* ``jacobi`` (a, b): ξ on [-1, 1] with density ∝ (1 − ξ)^a (1 + ξ)^b, a, b > −1 (the Beta(b + 1, a + 1) law mapped onto
  [-1, 1]); a = b = 0 is Legendre;
* ``truncated_hermite`` (a, b): ξ ~ N(0, 1) truncated to [a, b] (a < b, either may be infinite). No classical family
  belongs to it; its recurrence coefficients come from the discretised Stieltjes procedure (Gautschi 2004, §2.2.3.1):
  the inner products are sums over :data:`STIELTJES_NODES` Gauss-Legendre nodes of [max(a, −12), min(b, 12)] (the
  standard normal holds less than 1e-32 beyond ±12) weighted by the normal density, exact to round-off for the
  degrees a PCE uses (the integrands are a polynomial times an entire function). Truncated-normal inputs then keep
  an exact polynomial expansion of polynomial responses, as chaospy's ``stieltjes`` expansion does.

Hermite, Jacobi and truncated Hermite are evaluated with the three-term recurrence of the orthonormal polynomials
(Gautschi 2004, Orthogonal Polynomials, §1.3), sqrt(β_{n+1}) φ_{n+1} = (ξ − α_n) φ_n − sqrt(β_n) φ_{n−1},
φ_{−1} = 0, φ_0 = 1, with Hermite α_n = 0, β_n = n, and Jacobi

    α_n = (b² − a²) / ((2n + a + b)(2n + a + b + 2))          (α_0 = (b − a)/(a + b + 2)),
    β_n = 4n(n + a)(n + b)(n + a + b) / ((2n + a + b)² (2n + a + b + 1)(2n + a + b − 1))
                                                              (β_1 = 4(1 + a)(1 + b) / ((2 + a + b)² (3 + a + b))).

Legendre keeps Bonnet's recurrence, the one the basis always used, so uniform inputs give the same numbers as before.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from spflow.core.errors import ParameterError

__all__ = ["PolynomialFamily", "LEGENDRE", "HERMITE", "jacobi", "truncated_hermite", "FAMILIES", "univariate_table",
           "STIELTJES_NODES"]

#: The family names, in the order of their codes in the compiled evaluation.
FAMILIES = ("legendre", "hermite", "jacobi", "truncated_hermite")
#: Gauss-Legendre nodes of the discretised Stieltjes procedure (truncated Hermite).
STIELTJES_NODES = 200
#: The truncated Hermite inner products ignore the standard normal beyond ± this.
NORMAL_REACH = 12.0


@dataclass(frozen=True)
class PolynomialFamily:
    """One orthonormal family: ``name`` in :data:`FAMILIES`; ``a``, ``b`` the Jacobi exponents or the truncation
    interval of the truncated Hermite family (0 otherwise)."""

    name: str
    a: float = 0.0
    b: float = 0.0

    def __post_init__(self):
        if self.name not in FAMILIES:
            raise ParameterError(f"polynomial family {self.name!r} is not known; allowed: {list(FAMILIES)}")
        if self.name == "jacobi" and not (self.a > -1.0 and self.b > -1.0 and np.isfinite([self.a, self.b]).all()):
            raise ParameterError(f"Jacobi polynomials need exponents a, b > -1, got a = {self.a}, b = {self.b}")
        if self.name == "truncated_hermite" and not (self.a < self.b and self.a < NORMAL_REACH
                                                     and self.b > -NORMAL_REACH):
            raise ParameterError(f"truncated Hermite polynomials need a truncation interval a < b that meets "
                                 f"[-{NORMAL_REACH:g}, {NORMAL_REACH:g}], got a = {self.a}, b = {self.b}")

    @property
    def support(self) -> tuple[float, float]:
        """(lower, upper) of the reference variable: [-1, 1] (Legendre, Jacobi), the real line (Hermite), [a, b]
        (truncated Hermite)."""
        return {"hermite": (-np.inf, np.inf), "truncated_hermite": (self.a, self.b)}.get(self.name, (-1.0, 1.0))

    def recurrence(self, degree: int) -> tuple[np.ndarray, np.ndarray]:
        """(α_n, sqrt(β_n)) for n = 0..degree of the orthonormal recurrence (module docstring); sqrt(β_0) = 1 (a
        probability measure). Legendre's are Jacobi's at a = b = 0 (β_n = n² / (4n² − 1)), though
        :func:`univariate_table` evaluates Legendre with Bonnet's form."""
        if self.name == "truncated_hermite":
            return _stieltjes(self.a, self.b, degree)
        n = np.arange(degree + 1, dtype=float)
        alpha, beta = np.zeros(degree + 1), np.ones(degree + 1)
        if self.name == "hermite":
            beta[1:] = n[1:]
        else:  # Jacobi; Legendre has a = b = 0
            a, b = self.a, self.b
            s = 2.0 * n + a + b
            alpha[0] = (b - a) / (a + b + 2.0)
            alpha[1:] = (b * b - a * a) / (s[1:] * (s[1:] + 2.0))
            if degree >= 1:
                beta[1] = 4.0 * (1.0 + a) * (1.0 + b) / ((2.0 + a + b) ** 2 * (3.0 + a + b))
            m, t = n[2:], s[2:]
            beta[2:] = 4.0 * m * (m + a) * (m + b) * (m + a + b) / (t**2 * (t + 1.0) * (t - 1.0))
        return alpha, np.sqrt(beta)

    def evaluate(self, z: np.ndarray, degree: int) -> np.ndarray:
        """φ_0..φ_degree at points ``z`` (n,), shape (degree + 1, n)."""
        z = np.ascontiguousarray(np.atleast_1d(np.asarray(z, dtype=float)))[None, :]
        return univariate_table(z, (self,), degree)[0]


LEGENDRE = PolynomialFamily("legendre")
HERMITE = PolynomialFamily("hermite")


def jacobi(a: float, b: float) -> PolynomialFamily:
    """The Jacobi family orthonormal under the density ∝ (1 − ξ)^a (1 + ξ)^b on [-1, 1]."""
    return PolynomialFamily("jacobi", float(a), float(b))


def truncated_hermite(a: float, b: float) -> PolynomialFamily:
    """The family orthonormal under N(0, 1) truncated to [a, b]."""
    return PolynomialFamily("truncated_hermite", float(a), float(b))


@lru_cache(maxsize=256)
def _stieltjes(a: float, b: float, degree: int) -> tuple[np.ndarray, np.ndarray]:
    """Discretised Stieltjes procedure for N(0, 1) truncated to [a, b] (module docstring)."""
    lo, hi = max(a, -NORMAL_REACH), min(b, NORMAL_REACH)
    nodes, weights = np.polynomial.legendre.leggauss(STIELTJES_NODES)
    x = lo + 0.5 * (nodes + 1.0) * (hi - lo)
    w = weights * np.exp(-0.5 * x * x)
    w /= w.sum()
    alpha, sqrt_beta = np.zeros(degree + 1), np.ones(degree + 1)
    p_prev, p_cur = np.zeros_like(x), np.ones_like(x)
    for n in range(degree + 1):
        alpha[n] = np.sum(w * x * p_cur * p_cur)
        if n == degree:
            break
        nxt = (x - alpha[n]) * p_cur - sqrt_beta[n] * p_prev
        sqrt_beta[n + 1] = np.sqrt(np.sum(w * nxt * nxt))
        p_prev, p_cur = p_cur, nxt / sqrt_beta[n + 1]
    alpha.flags.writeable = sqrt_beta.flags.writeable = False
    return alpha, sqrt_beta


def _table(zt, codes, alpha, sqrt_beta, max_degree):  # pragma: no cover - compiled by _compiled_table
    d, n = zt.shape
    table = np.empty((d, max_degree + 1, n))
    for k in range(d):
        for i in range(n):
            x = zt[k, i]
            table[k, 0, i] = 1.0
            if codes[k] == 0:  # Legendre, Bonnet's recurrence on P_n, then sqrt(2n+1)
                p_prev, p_cur = 1.0, x
                if max_degree >= 1:
                    table[k, 1, i] = x * np.sqrt(3.0)
                for m in range(1, max_degree):
                    p_next = ((2 * m + 1) * x * p_cur - m * p_prev) / (m + 1)
                    p_prev, p_cur = p_cur, p_next
                    table[k, m + 1, i] = p_next * np.sqrt(2.0 * m + 3.0)
            else:  # orthonormal three-term recurrence
                p_prev, p_cur = 0.0, 1.0
                for m in range(max_degree):
                    p_next = ((x - alpha[k, m]) * p_cur - sqrt_beta[k, m] * p_prev) / sqrt_beta[k, m + 1]
                    p_prev, p_cur = p_cur, p_next
                    table[k, m + 1, i] = p_next
    return table


def univariate_table(zt: np.ndarray, families, max_degree: int) -> np.ndarray:
    """φ_m(ξ_k) for each reference coordinate k: ``zt`` (d, n) (coordinates as rows), one family per row;
    returns (d, max_degree + 1, n)."""
    if len(families) != zt.shape[0]:
        raise ParameterError(f"basis: {len(families)} polynomial families for {zt.shape[0]} coordinates")
    codes, alpha, sqrt_beta = _coefficients(tuple(families), max_degree)
    return _compiled_table()(np.ascontiguousarray(zt, dtype=float), codes, alpha, sqrt_beta, max_degree)


@lru_cache(maxsize=1)
def _compiled_table():
    """:func:`_table` compiled by numba, which loads on the first evaluation (not when the families are imported:
    ``spflow list`` imports the surrogate kinds)."""
    from numba import njit

    return njit(cache=True)(_table)


@lru_cache(maxsize=64)
def _coefficients(families: tuple[PolynomialFamily, ...], max_degree: int) -> tuple[np.ndarray, ...]:
    """Family codes (d,) and recurrence coefficients (d, max_degree + 1) of :func:`univariate_table` (read-only)."""
    d = len(families)
    codes = np.array([FAMILIES.index(f.name) for f in families], dtype=np.int64)
    alpha, sqrt_beta = np.zeros((d, max_degree + 1)), np.ones((d, max_degree + 1))
    for k, family in enumerate(families):
        if family.name != "legendre":
            alpha[k], sqrt_beta[k] = family.recurrence(max_degree)
    for a in (codes, alpha, sqrt_beta):
        a.flags.writeable = False
    return codes, alpha, sqrt_beta
