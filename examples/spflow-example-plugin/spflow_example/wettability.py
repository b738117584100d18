"""Effect ``wettability_alteration``: surfactant-induced shift towards water-wet, lowering the residual oil at low
capillary number, ``S2RWC -> (1 - 0.5 s) S2RWC`` (the Eq. 2.12 low-N_c end of the desaturation curve)."""

import spflow


def _lower_residual_oil(params: dict, strength: float) -> dict:
    return dict(params, S2RWC=params["S2RWC"] * (1.0 - 0.5 * strength))


WETTABILITY_ALTERATION = spflow.Effect(
    "wettability_alteration",
    "residual oil at low capillary number lowered by a shift to water-wet: S2RWC -> (1 - 0.5 s) S2RWC",
    default_strength=0.0,
    lower=0.0,
    upper=1.0,
    transform_params=_lower_residual_oil,
)
