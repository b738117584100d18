"""Brooks-Corey capillary pressure scaled with the interfacial tension (thesis Eq. 1.8)."""

from numba import njit

LEVERETT_FACTOR_MAX = 1000.0  # cap on S_bar^(-1/lambda_b): Pc stays finite as S_bar -> 0


@njit(cache=True, error_model="numpy")
def brooks_corey_pc(pc0, sbar, lambda_b, sigma, sigma_ref):
    """``Pc = pc0 min(S_bar^(-1/lambda_b), 1000) sigma / sigma_ref``, Eq. 1.8 with IFT scaling.

    ``pc0`` entry pressure at ``sigma_ref`` (any pressure unit; returned in the same unit), ``sbar`` normalized
    wetting saturation, ``lambda_b`` pore-size-distribution index (> 0), ``sigma``/``sigma_ref`` current and reference
    IFT (same unit). Eq. 1.8 diverges as ``S_bar -> 0``; the saturation factor is capped at ``LEVERETT_FACTOR_MAX``
    = 1000 (reached at ``S_bar = 1000^-lambda_b``) so that the explicit capillary flux stays bounded. Pc scales
    linearly with IFT (Leverett), so ultra-low IFT removes capillary effects.
    """
    if sbar > 0.0:
        factor = sbar ** (-1.0 / lambda_b)
        if factor > LEVERETT_FACTOR_MAX:
            factor = LEVERETT_FACTOR_MAX
    else:
        factor = LEVERETT_FACTOR_MAX
    return pc0 * factor * sigma / sigma_ref
