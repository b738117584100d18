"""Held-out scores from the sampled posterior predictive, without the linearisation (docs/gap.md, Method:
**Scores**; the ``heldout_predictive = "sampled"`` option).

The linearised predictive of :mod:`~spflow.plugins.gap.predictive_scores` centres a calibrated model's prediction
of the held-out coreflood at its optimum and spreads it with the Jacobian there. Where the calibration coreflood
leaves a valley of parameter sets with nearly the same fit, the optimum can sit at the far end of the valley (a
parameter at its bound) where the held-out prediction is both wrong and steep; the linearised predictive then
scores the model far below one whose valley it shares (docs/gap.md: on twins, the truth's own refit scores 16-80
nats below the base while the exact truth scores 4-47 nats above it). The posterior predictive integrates over the
valley:

    p(y_held | y_cal) = int p(y_held | z) p(z | y_cal) dz,   p(z | y_cal) ~ exp(-chi2_cal(z) / 2) on the unit box

(the posterior of the bounded least squares the calibration solves: a flat prior on the box). It is estimated by
self-normalised importance sampling with the Laplace posterior as proposal: ``z_k ~ N(z_hat, C)`` truncated to the
box, ``C`` the linearised covariance of :func:`~spflow.plugins.gap.quantification.parameter_covariance`,
log weights ``-chi2_cal(z_k) / 2 - log q(z_k)`` Pareto-smoothed (PSIS; Vehtari, Simpson, Gelman, Yao & Gabry 2024)
and normalised, and

    p(y_held | y_cal) ~ sum_k w_k N(y_held; y_held(z_k), Sigma)

in the whitened metric of the shared error model, where ``N`` reduces to ``exp(-|h_k|^2 / 2)`` with ``h_k`` the
whitened held-out residuals of draw ``k`` (constants shared by all models dropped, as in the linearised terms). Its
sequential pointwise terms ``log p(y_1..i) - log p(y_1..i-1)`` sum to the total; the gradient ``sum_k r_k h_k``
(``r_k`` the draws' posterior responsibilities given the held-out data) takes the place of ``S^-1 w`` in the
measurement SE, and the whitened residual reported is that of the predictive mean, ``sum_k w_k h_k``.

The Monte Carlo error of the estimate ``p_hat = sum_k w_k L_k`` (``L_k = exp(-|h_k|^2 / 2)``) is the delta-method
standard error of a self-normalised importance-sampling estimate (Owen 2013, *Monte Carlo theory, methods and
examples*, ch. 9), ``var(p_hat) ~ sum_k w_k^2 (L_k - p_hat)^2``; on the log scale
``mcse = sqrt(sum_k (r_k - w_k)^2)`` with ``r_k = w_k L_k / p_hat`` the responsibilities. It treats the draws as
independent (the Gibbs top-up's are correlated) and ignores the Pareto smoothing; it is reported, not used by the
decision rule.

The truncated proposal is sampled by rejection from ``N(m, C)``; where the mean sits in a corner of the box
with a wide posterior so that too few of ``_POOL`` proposals per draw fall inside, the rest come from a Gibbs
sampler of the same truncated normal (each coordinate from its conditional normal truncated to [0, 1]; Geweke
1991), started at the proposal's mean clipped to the box. Both give draws of one density whose normalising constant
cancels in the self-normalised weights, ``-log q = (z - m)' C^-1 (z - m) / 2`` with ``m`` the proposal's mean: the
optimum ``z_hat``, or with ``centre = "newton"`` the minimiser of the Gauss-Newton model of the calibration chi2 at
the fit, ``m = z_hat - C J'r`` (``J``, ``r`` the fit's whitened Jacobian and residuals; outside the box when the
gradient presses the fit on a face, where the truncation then piles the draws). The optimiser stops short of the
optimum on a calibration chi2 made rough by the forward model's jumps in the parameters, and a fit on a face with a
large gradient has its posterior within ``~1/g`` of the face: a proposal centred on ``z_hat`` then sits several
posterior sd off the mode and the weights degenerate (docs/gap.md, Scores). The estimate is only as good as the
proposal covers the posterior: its effective sample size ``1 / sum w_k^2`` and the Pareto ``k`` of the weights
(``k > 0.7``: unreliable) are returned with it, and the Monte Carlo error of the log predictive. Coordinate
``j``'s standard normals come from the stream ``(seed, j)``, so models sharing calibrated parameters share their
draws' randomness (common random numbers), and a rerun reproduces every score.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.linalg import cholesky
from scipy.special import logsumexp, softmax
from scipy.stats import truncnorm

from spflow.plugins.calibration.diagnostics import arviz

from .least_squares import Fit
from .predictive_scores import Predictive
from .quantification import parameter_covariance

__all__ = ["HELDOUT_PREDICTIVES", "PROPOSAL_CENTRES", "RELIABLE_PARETO_K", "is_unreliable", "mixture_terms",
           "posterior_draws", "proposal_mean", "sampled_predictive", "unreliable_weights_note"]

#: held-out predictive distributions of a calibrated model: linearised at the optimum, or sampled (module docstring)
HELDOUT_PREDICTIVES = ("laplace", "sampled")
#: where the sampled predictive's proposal is centred: at the optimum, or at its Gauss-Newton model's minimiser
PROPOSAL_CENTRES = ("optimum", "newton")

#: above this Pareto k of the importance weights the estimate is unreliable (Vehtari et al. 2024)
RELIABLE_PARETO_K = 0.7

#: proposals drawn per requested draw before the truncation to the unit box
_POOL = 20
#: Gibbs sweeps discarded before the first kept draw, and sweeps between kept draws
_BURN_IN, _THIN = 20, 2

Residuals = Callable[[list[np.ndarray]], list[np.ndarray]]


def proposal_mean(fitted: Fit, cov: np.ndarray, centre: str) -> np.ndarray:
    """The proposal's mean: the optimum ``z_hat`` (``centre = "optimum"``), or the minimiser of the Gauss-Newton
    model of the calibration chi2 there, ``z_hat - C J'r`` with ``C = cov`` (``"newton"``; module docstring), not
    restricted to the box."""
    if centre == "optimum":
        return fitted.z
    ok = np.all(np.isfinite(fitted.jacobian), axis=1) & np.isfinite(fitted.residual)
    return fitted.z - cov @ (fitted.jacobian[ok].T @ fitted.residual[ok])


def is_unreliable(pareto_k: float | None) -> bool:
    """Whether importance weights with this Pareto k give an unreliable estimate (``k > RELIABLE_PARETO_K``; an
    undefined k -- NaN, or ``None`` as a report stores it -- counts as unreliable)."""
    return pareto_k is None or not pareto_k <= RELIABLE_PARETO_K


def posterior_draws(fitted: Fit, tau: float, draws: int, seed: int, pool: int = _POOL,
                    centre: str = "optimum") -> tuple[np.ndarray, np.ndarray]:
    """(draws, q) unit-box coordinates from ``N(m, C)`` truncated to the box, ``m`` the :func:`proposal_mean` of
    ``centre`` -- by rejection from ``pool * draws`` proposals, topped up by Gibbs sampling when fewer fall inside --
    and ``-log q`` of each up to a constant (module docstring)."""
    ok = np.all(np.isfinite(fitted.jacobian), axis=1)
    cov = parameter_covariance(fitted.jacobian[ok], tau)
    mean = proposal_mean(fitted, cov, centre)
    factor = cholesky(cov, lower=True)
    q = factor.shape[0]
    e = np.column_stack([np.random.default_rng([seed, j]).standard_normal(pool * draws) for j in range(q)])
    z = mean[None, :] + e @ factor.T
    z = z[np.all((z >= 0.0) & (z <= 1.0), axis=1)][:draws]
    precision = np.linalg.inv(cov)
    if len(z) < draws:
        z = np.vstack([z, _gibbs(mean, precision, draws - len(z), np.random.default_rng([seed, q]))])
    d = z - mean[None, :]
    return z, 0.5 * np.einsum("ki,ij,kj->k", d, precision, d)


def _gibbs(mean: np.ndarray, precision: np.ndarray, draws: int, rng: np.random.Generator) -> np.ndarray:
    """``draws`` states of a Gibbs sampler of ``N(mean, precision^-1)`` truncated to the unit box, started at
    ``mean`` clipped to the box, after ``_BURN_IN`` sweeps and every ``_THIN`` sweeps."""
    z = np.clip(mean, 0.0, 1.0).astype(float)
    sd = 1.0 / np.sqrt(np.diag(precision))
    out = []
    for sweep in range(_BURN_IN + _THIN * draws):
        for j in range(z.size):
            m = mean[j] - (precision[j] @ (z - mean) - precision[j, j] * (z[j] - mean[j])) / precision[j, j]
            z[j] = truncnorm.rvs((0.0 - m) / sd[j], (1.0 - m) / sd[j], loc=m, scale=sd[j], random_state=rng)
        if sweep >= _BURN_IN and (sweep - _BURN_IN) % _THIN == _THIN - 1:
            out.append(z.copy())
    return np.array(out)


def mixture_terms(log_weights: np.ndarray, held: np.ndarray) -> Predictive:
    """Predictive terms of the mixture ``sum_k w_k N(h; h_k, I)`` of the draws' whitened held-out residuals
    ``held`` (draws x points) with normalised ``log_weights`` (module docstring)."""
    running = logsumexp(log_weights[:, None] - 0.5 * np.cumsum(held**2, axis=1), axis=0)
    lpd = np.diff(np.concatenate([[logsumexp(log_weights)], running]))
    responsibilities = softmax(log_weights - 0.5 * np.sum(held**2, axis=1))
    weights = softmax(log_weights)
    return Predictive(lpd, responsibilities @ held, weights @ held, ess=float(1.0 / np.sum(weights**2)),
                      mcse=float(np.linalg.norm(responsibilities - weights)))


def sampled_predictive(calibration: Residuals, heldout: Residuals, fitted: Fit, *, tau: float, draws: int,
                       seed: int, shift: np.ndarray | None = None, pool: int = _POOL,
                       centre: str = "optimum") -> Predictive:
    """Sampled posterior predictive terms of the held-out points under ``fitted`` (module docstring).

    ``calibration`` and ``heldout``: whitened residuals of the calibration and held-out points at a batch of
    unit-box coordinates (``WhitenedProblem.residuals``); ``shift``: whitened shift of the held-out predictions (a
    transferred discrepancy); ``pool``: proposals per draw for the rejection sampler (0: Gibbs draws only);
    ``centre``: the proposal's mean (:func:`proposal_mean`)."""
    zs, neg_log_q = posterior_draws(fitted, tau, draws, seed, pool, centre)
    points = list(zs)
    chi2 = np.array([r @ r for r in calibration(points)])
    held = np.array(heldout(points))
    if shift is not None:
        held = held + shift[None, :]
    az = arviz()
    log_weights, k = az.psislw(-0.5 * chi2 + neg_log_q)
    out = mixture_terms(np.asarray(log_weights, float), held)
    return Predictive(out.lpd, out.gradient, out.whitened, ess=out.ess, pareto_k=float(k), mcse=out.mcse)


def unreliable_weights_note(unreliable: dict[str, tuple[float, float, float]], draws: int) -> str:
    """The diagnosis's note naming the models whose sampled held-out score is unreliable: ``unreliable`` maps a
    model's label to (Pareto k, effective sample size, Monte Carlo SE in nats) of its importance weights,
    ``draws`` the draws taken."""
    listed = "; ".join(f"{m} (k {k:.2f}, ESS {ess:.1f}, Monte Carlo SE {mcse:.2f})"
                       for m, (k, ess, mcse) in sorted(unreliable.items(), key=lambda x: -x[1][0]))
    return (f"the sampled held-out score is unreliable for {len(unreliable)} model(s), Pareto k > "
            f"{RELIABLE_PARETO_K} over {draws} draws: {listed}. Each rests on a few draws: its Monte Carlo SE "
            "understates its error and another seed of the draws can change the ambiguity set (docs/gap.md, Scores: "
            "a calibration chi2 rough at the posterior's scale, a fit short of its optimum or pressed on the "
            "parameter box). Check the verdict with another seed, or with heldout_predictive = 'laplace'")
