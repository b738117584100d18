"""Effective salinities seen by the polymer and by the surfactant phase behaviour (thesis Eq. 2.3; UTCHEM).

Units: concentrations of anions (component 5) and divalent cations (component 6) in meq/ml, water (component 1) as a
volume fraction of the phase; the results are in meq/ml.
"""

from numba import njit


@njit(cache=True, error_model="numpy")
def polymer_effective_salinity(c51, c61, c11, betap):
    """Effective salinity for polymer viscosity, ``C_SEP = (C51 + (BETAP - 1) C61) / C11`` (meq/ml), Eq. 2.3.

    The thesis prints ``C51 - (BETAP - 1) C61``; the UTCHEM-9.0 Technical Documentation §2 uses a plus sign, so divalent
    cations count BETAP times as much as monovalent ones. The plus sign is used here. ``c51``/``c61`` in meq/ml of
    the aqueous (polymer-carrying) phase, ``c11`` water volume fraction of that phase (> 0), ``betap`` dimensionless.
    """
    return (c51 + (betap - 1.0) * c61) / c11


@njit(cache=True, error_model="numpy")
def phase_behaviour_effective_salinity(c51, beta6, f6s):
    """Effective salinity for phase behaviour without alcohol, ``C_SE = C51 / (1 - BETA6 f6s)`` (meq/ml).

    ``c51`` anion concentration (meq/ml), ``beta6`` divalent-cation slope parameter (BETA6, dimensionless), ``f6s``
    fraction of the divalent cations bound to micelles (0..1); requires ``beta6 * f6s < 1`` (UTCHEM-9.0 Technical
    Documentation §2).
    """
    return c51 / (1.0 - beta6 * f6s)
