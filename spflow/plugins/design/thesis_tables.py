"""The thesis's uncertain-parameter boxes in UTCHEM names (forward-model units, `spflow list params`).

Names: alpha_V2 = ALPHAV2, C33max0 = HBNC70, C33max1 = HBNC71, ad31 = AD31, gamma_1/2 = GAMHF (1/s), c_rk = CRK,
n_high = E2C and n_low = E2WC (oleic-phase Corey exponents at high and low capillary number), alpha_L1 = ALPHAL1 (ft).
"""

#: Table 3.2: ranges of the proxy model's inputs (chapter 3, history matching with NSGA-II).
TABLE_3_2 = {
    "ALPHAV2": [0.0, 3.0],
    "HBNC70": [0.02, 0.05],
    "HBNC71": [0.01, 0.02],
    "AD31": [0.0, 2.0],
    "GAMHF": [55.0, 100.0],
    "CRK": [0.05, 0.1],
    "E2C": [1.5, 3.0],
    "E2WC": [1.5, 3.0],
    "ALPHAL1": [0.008, 0.012],
}

#: Table 4.1: prior ranges of the Bayesian calibration (chapter 4).
TABLE_4_1 = {
    "ALPHAV2": [2.5, 3.0],
    "HBNC70": [0.02, 0.035],
    "HBNC71": [0.01, 0.02],
    "AD31": [0.1, 1.0],
    "GAMHF": [50.0, 70.0],
    "CRK": [0.06, 0.08],
    "E2C": [1.5, 2.5],
    "E2WC": [1.5, 2.5],
    "ALPHAL1": [0.008, 0.012],
}
