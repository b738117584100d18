"""Tertiary surfactant / surfactant-polymer flood (Larson & Hirasaki 1978; Pope 1980; Lake ch. 9).

The core starts at waterflood residual, ``S_wI = 1 - S_orw`` (``f_w = 1``: no oil flows). Behind the chemical front
the high-capillary-number curve ``f_c`` applies (high-Nc residuals/end points/exponents, slug aqueous viscosity);
the chemical line through ``(S_1, f_c(S_1))`` with slope ``lambda_c`` meets the low-Nc ``f_w`` at the bank saturation
``S_B < S_wI``, and the bank front moves at ``lambda_B = (1 - f_w(S_B))/(S_wI - S_B)``. No oil is produced before
the bank breaks through. The construction is :func:`oracles.polymer_riemann.chemical_flood` with that initial state.
"""

from oracles.polymer_riemann import ChemicalFlood, chemical_flood


def tertiary_chemical_flood(
    f_w_low, f_c_high, *, retardation: float = 0.0, ipv: float = 0.0, ipv_form: str = "offset"
) -> ChemicalFlood:
    """Continuous chemical injection into a core at waterflood residual oil ``S_wI = f_w_low.s_max``.

    Raises ``ValueError`` if no positive oil bank forms (needs the chemical line to meet ``f_w`` below ``S_wI``,
    i.e. a high-Nc residual oil below the waterflood residual).
    """
    s_init = f_w_low.s_max
    flood = chemical_flood(
        f_w_low, f_c_high, s_init, retardation=retardation, ipv=ipv, ipv_form=ipv_form
    )
    if not flood.s_bank < s_init - 1e-12:
        raise ValueError(f"no oil bank: bank saturation {flood.s_bank} is not below S_wI = {s_init}")
    return flood


def slug_consumption_distance(slug_pv: float, retardation: float) -> float:
    """``x_D`` at which a single-phase chemical slug of ``slug_pv`` PV is used up by irreversible adsorption.

    The adsorption front moves at ``1/((1 - phi_IPV) + D)`` and the slug rear at ``1/(1 - phi_IPV)``; they meet at
    ``x_D = t_s / D`` whatever the (scaled) inaccessible pore volume.
    """
    if not slug_pv > 0.0:
        raise ValueError(f"slug_pv must be > 0, got {slug_pv}")
    if not retardation > 0.0:
        raise ValueError(f"retardation (D, PV units) must be > 0 for the slug to be consumed, got {retardation}")
    return slug_pv / retardation
