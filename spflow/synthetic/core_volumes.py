"""Pore volume and original oil in place of a cylindrical core, in ml (the lab's units for tube readings)."""

from __future__ import annotations

import math
from collections.abc import Mapping

__all__ = ["pore_volume_ml", "ooip_ml"]


def pore_volume_ml(params: Mapping[str, float]) -> float:
    """``pi D^2 / 4 * L * PORO`` in ml, from ``LENGTH`` and ``DIAMETER`` (m) and ``PORO`` (-)."""
    return math.pi * params["DIAMETER"] ** 2 / 4.0 * params["LENGTH"] * params["PORO"] * 1.0e6


def ooip_ml(params: Mapping[str, float]) -> float:
    """Original oil in place ``PV (1 - SWI)`` in ml."""
    return pore_volume_ml(params) * (1.0 - params["SWI"])
