"""Independent analytic references for validating the spflow forward model.

Nothing in this package imports :mod:`spflow`: every reference is written from fractional-flow theory
(Buckley-Leverett/Welge; Pope 1980; Larson & Hirasaki 1978; Lake 1989) and their closed forms (docs/forward_model.md,
Verification), using only numpy/scipy. Dimensionless conventions: ``x_D = x/L``,
``t_D`` = injected pore volumes (PV), ``xi = x_D/t_D``.
"""

from oracles.adsorption import langmuir_retardation
from oracles.buckley_leverett import buckley_leverett, welge_front_saturation
from oracles.comparison import cell_average, crossing_time, interval_midpoints, l1_error, observed_order
from oracles.corey import CoreyFractionalFlow
from oracles.ogata_banks import ogata_banks, ogata_banks_time_at, retarded_midpoint_pv
from oracles.polymer_pressure import (
    flory_huggins_viscosity,
    permeability_reduction,
    piston_pressure_ratio,
)
from oracles.polymer_riemann import ChemicalFlood, chemical_flood, chemical_front_saturation, storage_coefficients
from oracles.sp_riemann import slug_consumption_distance, tertiary_chemical_flood
from oracles.utchem_names import corey_params
from oracles.wave_fan import Segment, WaveFan, rarefaction_saturation

__all__ = [
    "ChemicalFlood",
    "CoreyFractionalFlow",
    "Segment",
    "WaveFan",
    "buckley_leverett",
    "cell_average",
    "chemical_flood",
    "chemical_front_saturation",
    "corey_params",
    "crossing_time",
    "flory_huggins_viscosity",
    "interval_midpoints",
    "l1_error",
    "langmuir_retardation",
    "ogata_banks",
    "ogata_banks_time_at",
    "observed_order",
    "permeability_reduction",
    "piston_pressure_ratio",
    "rarefaction_saturation",
    "retarded_midpoint_pv",
    "slug_consumption_distance",
    "storage_coefficients",
    "tertiary_chemical_flood",
    "welge_front_saturation",
]
