"""The screening space of thesis Table 3.1: 19 fitting parameters of seven sub-models, in UTCHEM names.

``TABLE_3_1`` maps each sub-model (Table 3.1's "Model Name") to its parameters; ``TABLE_3_1_RANGES`` holds the
explicit ranges; every other parameter gets the ``parameter_space`` stage's ``relative`` = ±20 % around its
Table 2.4 calibrated default (Algorithm 1, step 5), clipped to the catalogue's physical bounds. A pipeline builds the
space with::

    p.add("space", "parameter_space", params={"names": table_3_1_names(), "ranges": TABLE_3_1_RANGES})

and screens it per sub-model with ``groups=TABLE_3_1`` (Algorithm 1's loop over the models M_i).

Range choices (±20 % unless listed; defaults from ``spflow.plugins.forward.parameters``):

=============  ========================  ==================================================================
parameter      range                     why
=============  ========================  ==================================================================
ALPHAV1,4,5    ±20 %                     Table 2.4 calibration (2, 0.9, 0.7) ± 20 %
ALPHAV2        [0, 3]                    Table 3.2 literature range of alpha_V2
ALPHAV3        [0, 3] cP                 default 0 (±20 % would be a point). Same span as Table 3.2 gives
                                         ALPHAV2 from the same literature; the term C3 alpha_V3 e^(...) of
                                         Eq. 2.11 stays below ~0.2 cP at the calibrated binodal heights, so
                                         ALPHAV3 is expected to be nearly inert
HBNC70         [0.02, 0.05]              Table 3.2 (C33max0, experiment)
HBNC71         [0.01, 0.02]              Table 3.2 (C33max1, experiment)
HBNC72         ±20 %                     Table 2.4 0.02 ± 20 %
AD31           [0, 2]                    Table 3.2 (ad31, experiment)
AD32           [0, 2] ml/meq             default 0 (the thesis assumes no salinity effect). At BCF1's
                                         9 400 ppm brine (C_SE = 0.145 meq/ml) AD32 = 2 adds 0.29 to
                                         a_3 = AD31 + AD32 C_SE (Eq. 2.16), about the calibrated AD31 = 0.31:
                                         the range spans "no salinity effect" to "adsorption doubles"
B3D            ±20 %                     Table 2.4 100 ± 20 %
GAMHF          [55, 100] 1/s             Table 3.2 (gamma_1/2, experiment)
CRK            [0.05, 0.1]               Table 3.2 (c_rk, experiment)
BRK            ±20 %                     Table 2.4 100 ± 20 %
E2C, E2WC      [1.5, 3]                  Table 3.2 (n_high, n_low, ref. [130])
ALPHAL1        [0.008, 0.012] ft         Table 3.2 (= 0.01 ft ± 20 %)
ALPHAL2, 3     ±20 %                     Fig. 2.9 0.01 ft ± 20 %
=============  ========================  ==================================================================

n_high and n_low are the Corey exponents (Eq. 2.14) at high and low trapping number (Eq. 2.13 interpolates
between them). Table 3.1 gives one pair; we take the **oleic** phase's pair E2C (high) and E2WC (low), as the
``prior_spread`` pipeline does: the oil exponent shapes k_ro at low oil saturation, i.e. the recovery tail the
QoIs measure, while the aqueous (E1C/E1WC) and microemulsion (E3C/E3WC) exponents stay at their defaults of 2.

Caveat: the Table 3.2 ranges are the thesis's proxy ranges, several times wider than ±20 % for ALPHAV2, AD31,
HBNC70 and the Corey exponents. A wider range raises a parameter's variance share, so screening on this space
favours the parameters the thesis kept; ``ranges={}`` screens the pure ±20 % space of Algorithm 1 instead.
"""

from __future__ import annotations

__all__ = ["TABLE_3_1", "TABLE_3_1_RANGES", "table_3_1_names"]

#: Sub-model (Table 3.1 "Model Name") -> its fitting parameters in UTCHEM names, in the table's order.
TABLE_3_1: dict[str, list[str]] = {
    "micro-emulsion viscosity": ["ALPHAV1", "ALPHAV2", "ALPHAV3", "ALPHAV4", "ALPHAV5"],
    "phase behaviour": ["HBNC70", "HBNC71", "HBNC72"],
    "adsorption": ["AD31", "AD32", "B3D"],
    "polymer viscosity and shear": ["GAMHF"],
    "permeability reduction": ["CRK", "BRK"],
    "relative permeability": ["E2C", "E2WC"],
    "dispersivity": ["ALPHAL1", "ALPHAL2", "ALPHAL3"],
}

#: Explicit [low, high] ranges (module docstring); the others are ±20 % around the Table 2.4 defaults.
TABLE_3_1_RANGES: dict[str, list[float]] = {
    "ALPHAV2": [0.0, 3.0],
    "ALPHAV3": [0.0, 3.0],
    "HBNC70": [0.02, 0.05],
    "HBNC71": [0.01, 0.02],
    "AD31": [0.0, 2.0],
    "AD32": [0.0, 2.0],
    "GAMHF": [55.0, 100.0],
    "CRK": [0.05, 0.1],
    "E2C": [1.5, 3.0],
    "E2WC": [1.5, 3.0],
    "ALPHAL1": [0.008, 0.012],
}


def table_3_1_names() -> list[str]:
    """The 19 parameter names in Table 3.1's order."""
    return [name for names in TABLE_3_1.values() for name in names]
