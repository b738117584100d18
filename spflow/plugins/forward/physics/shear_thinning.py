"""Shear thinning of the polymer solution: Meter law (Eq. 2.4), half-shear rate law (Eq. 2.5), in-situ shear rate.

Units: viscosities in cP, shear rates in 1/s, polymer concentration in wt %, effective salinity in meq/ml.

In-situ shear-rate convention (UTCHEM-9.0 Technical Documentation §2): ``gamma_eq = GAMMAC |u| / sqrt(k k_r phi S)``
with GAMMAC
kept in UTCHEM field units (IUNIT = 0), day darcy^(1/2) / (ft s), so that the thesis value GAMMAC = 40 (Table 2.4,
taken from a UTCHEM field-unit deck) can be used verbatim. The kernel takes SI inputs (``u`` in m/s, ``k`` in m^2)
and converts them internally to ft/day and darcy. In SI the law reads
``gamma_eq = GAMMAC * SI_FACTOR * |u| / sqrt(k k_r phi S)`` with
``SI_FACTOR = DARCY_M2**0.5 / FT_PER_DAY_M_PER_S = 0.28161``, so GAMMAC = 40 is a dimensionless prefactor of 11.26
(for comparison, the capillary-bundle wall shear rate is ``sqrt(2) |u| / sqrt(k phi S)``; UTCHEM writes
GAMMAC = 3.97 C with C the shear-rate correction factor).
"""

import math

from numba import njit

FT_PER_DAY_M_PER_S = 0.3048 / 86400.0  # 1 ft/day in m/s
DARCY_M2 = 9.869233e-13  # 1 darcy in m^2
SI_FACTOR = math.sqrt(DARCY_M2) / FT_PER_DAY_M_PER_S  # dimensionless prefactor per unit GAMMAC in SI


@njit(cache=True, error_model="numpy")
def meter_viscosity(mu_w, mu0, gamma, gamma_half, pown):
    """Meter law ``mu_p = mu_w + (mu0 - mu_w) / (1 + (gamma/gamma_half)^(POWN - 1))`` (cP), Eq. 2.4.

    ``mu0`` is the zero-shear viscosity (Eq. 2.1), ``gamma`` the equivalent shear rate and ``gamma_half`` the shear rate
    at which ``mu_p - mu_w`` is halved (both 1/s), ``pown`` the Meter exponent (> 1 for shear thinning).
    Limits: ``gamma <= 0`` returns ``mu0``; ``gamma_half <= 0`` (e.g. the Eq. 2.5 fit clipped at zero) with
    ``gamma > 0`` returns ``mu_w``, the ``gamma_half -> 0+`` limit.
    """
    if gamma <= 0.0:
        return mu0
    if gamma_half <= 0.0:
        return mu_w
    return mu_w + (mu0 - mu_w) / (1.0 + (gamma / gamma_half) ** (pown - 1.0))


@njit(cache=True, error_model="numpy")
def half_shear_rate(csep, cp, a0, a1, a2):
    """Thesis half-shear-rate law ``gamma_half = (a1 C_SEP + a0) exp(a2 Cp)`` (1/s), Eq. 2.5, clipped at 0.

    Units: ``csep`` in meq/ml and ``cp`` in wt %, with the Table 2.4 constants (labelled "A0, A1, A2", values
    -588, 7683, -12; the table attributes them to Eq. 2.1 but they are the Eq. 2.5 constants) in 1/s, (1/s)/(meq/ml)
    and 1/(wt %). Derivation of the units: converting the coreflood brines as NaCl (58.44 g/eq), 9400 ppm = 0.161 and
    17500 ppm = 0.299 meq/ml; then gamma_half = 85.3 1/s at (0.299 meq/ml, 0.25 wt %) -- the high-salinity SP slug of
    BCF2/3 -- inside the 55-100 1/s prior of Table 3.2, and 12-85 1/s over Cp 0.25-0.33 wt %, 9400-17500 ppm
    (scaling the Table 2.1 brine instead, 0.145 meq/ml anions at 9400 ppm, gives 74 1/s for the same slug). Reading
    C_SEP in wt % instead gives 126-640 1/s and Cp in g/l gives < 2e-10 1/s, so only meq/ml and wt % are consistent
    with Table 3.2. The fit is positive only for ``csep > -a0/a1`` (0.0765 meq/ml for Table 2.4); below that the value
    is clipped at 0, for which ``meter_viscosity`` returns the solvent viscosity at any positive shear rate.
    """
    value = (a1 * csep + a0) * math.exp(a2 * cp)
    return value if value > 0.0 else 0.0


@njit(cache=True, error_model="numpy")
def equivalent_shear_rate(u, k, kr, phi, s, gammac):
    """UTCHEM in-situ shear rate ``gamma_eq = GAMMAC |u| / sqrt(k k_r phi S)`` (1/s), UTCHEM-9.0 Technical
    Documentation §2.

    ``u`` Darcy flux of the polymer-carrying phase in m/s, ``k`` permeability along the flow in m^2, ``kr`` relative
    permeability, ``phi`` porosity, ``s`` phase saturation, ``gammac`` in UTCHEM field units day darcy^(1/2)/(ft s)
    (see the module docstring: ``u`` is converted to ft/day and ``k`` to darcy). Returns 0 when ``k kr phi S <= 0``
    (an immobile or absent phase carries no flux and is not sheared).
    """
    mobility_scale = (k / DARCY_M2) * kr * phi * s
    if mobility_scale <= 0.0:
        return 0.0
    return gammac * (abs(u) / FT_PER_DAY_M_PER_S) / math.sqrt(mobility_scale)
