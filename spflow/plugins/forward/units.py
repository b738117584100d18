"""Unit conversions of the forward model, in one place.

The user-facing side speaks lab units (ppm, mD, ml/min, cP, ft for dispersivities); the kernel works in SI for
pressure and in UTCHEM concentration units for the chemistry (docs/forward_model.md, Physics and modelling choices):

* salinity: total dissolved solids (ppm, mg/l of brine)  ->  anions and divalent cations in meq/ml of water.
  The conversion scales the thesis brine linearly: Table 2.1 gives 0.145 meq/ml anions and 0.0097 meq/ml divalent
  cations for the synthetic brine, whose TDS is the 9 400 ppm of the IWF slugs (Table 2.5).  With this conversion
  17 500 ppm -> 0.270 meq/ml, inside the Table 2.4 type-III window (CSEL 0.255, CSEU 0.305 meq/ml), and 9 400 ppm
  -> 0.145 meq/ml, below it, as the thesis reports (section 2.5).  The divalent share is that of the same brine.
* surfactant: ppm -> volume fraction (1 ppm = 1e-6; the thesis's 6 780 ppm slug is its "0.678 %" surfactant).
* polymer: ppm -> wt % (1 wt % = 10 000 ppm).
"""

from __future__ import annotations

__all__ = [
    "TABLE21_TDS_PPM",
    "TABLE21_ANIONS_MEQ_ML",
    "TABLE21_DIVALENT_MEQ_ML",
    "ANIONS_PER_PPM",
    "DIVALENT_PER_PPM",
    "FT_TO_M",
    "MD_TO_M2",
    "MD_TO_DARCY",
    "ML_MIN_TO_M3_S",
    "CP_TO_PA_S",
    "MN_M_TO_N_M",
    "M_S_TO_FT_DAY",
    "tds_ppm_to_anions",
    "tds_ppm_to_divalent",
    "anions_to_tds_ppm",
    "surfactant_ppm_to_volume_fraction",
    "volume_fraction_to_surfactant_ppm",
    "polymer_ppm_to_wt_percent",
    "wt_percent_to_polymer_ppm",
]

#: TDS of the Table 2.1 synthetic brine, ppm (the 9 400 ppm IWF brine of Table 2.5).
TABLE21_TDS_PPM = 9400.0
#: Anion concentration of the Table 2.1 brine, meq/ml.
TABLE21_ANIONS_MEQ_ML = 0.145
#: Divalent-cation concentration of the Table 2.1 brine, meq/ml.
TABLE21_DIVALENT_MEQ_ML = 0.0097
#: meq/ml of anions per ppm TDS.
ANIONS_PER_PPM = TABLE21_ANIONS_MEQ_ML / TABLE21_TDS_PPM
#: meq/ml of divalent cations per ppm TDS.
DIVALENT_PER_PPM = TABLE21_DIVALENT_MEQ_ML / TABLE21_TDS_PPM

FT_TO_M = 0.3048
#: 1 mD = 9.869233e-16 m^2.
MD_TO_M2 = 9.869233e-16
MD_TO_DARCY = 1.0e-3
ML_MIN_TO_M3_S = 1.0e-6 / 60.0
CP_TO_PA_S = 1.0e-3
MN_M_TO_N_M = 1.0e-3
#: Darcy velocity m/s -> ft/day (UTCHEM field units of the shear-rate coefficient GAMMAC).
M_S_TO_FT_DAY = 86400.0 / FT_TO_M


def tds_ppm_to_anions(ppm: float) -> float:
    """Anion concentration (meq/ml) of a brine of ``ppm`` TDS (Table 2.1 brine scaled linearly)."""
    return ppm * ANIONS_PER_PPM


def tds_ppm_to_divalent(ppm: float) -> float:
    """Divalent-cation concentration (meq/ml) of a brine of ``ppm`` TDS (Table 2.1 divalent share)."""
    return ppm * DIVALENT_PER_PPM


def anions_to_tds_ppm(meq_ml):
    """Inverse of :func:`tds_ppm_to_anions` (works element-wise on arrays)."""
    return meq_ml / ANIONS_PER_PPM


def surfactant_ppm_to_volume_fraction(ppm: float) -> float:
    """Surfactant ppm -> volume fraction (1e-6 per ppm)."""
    return ppm * 1.0e-6


def volume_fraction_to_surfactant_ppm(fraction):
    """Surfactant volume fraction -> ppm (element-wise)."""
    return fraction * 1.0e6


def polymer_ppm_to_wt_percent(ppm: float) -> float:
    """Polymer ppm -> wt % (10 000 ppm = 1 wt %)."""
    return ppm * 1.0e-4


def wt_percent_to_polymer_ppm(wt_percent):
    """Polymer wt % -> ppm (element-wise)."""
    return wt_percent * 1.0e4
