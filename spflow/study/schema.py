"""The study file's schema, version 1: the allowed keys of every table, the roles, the quantity kinds and which
values may take a documented default. The full reference is ``docs/your_own_data.md``.

.. code-block:: toml

    version = 1
    [parameters.calibrated]              # name = [low, high] in the forward model's units, or a group table
    HBNC71 = [0.01, 0.02]
    n_high = { names = ["E1C", "E2C", "E3C"], range = [1.5, 3.0] }
    [parameters.fixed]                   # name = value (study-wide; not the per-experiment core data)
    VIS2 = 13.8
    [effects]                            # base-model effect strengths (unlisted: registry default, recorded)
    capillary_pressure = 0.0

    [[experiment]]
    name = "core7"
    role = "calibration"                 # calibration | heldout | predict
    data = "core7.csv"                   # CSV or netCDF, relative to the study file
    rate = "0.5 ml/min"                  # or from the data file's header / attrs
    schedule = "from data"               # or a TOML schedule file, a Table 2.5 name, or inline slugs
    [experiment.core]                    # each value with units (or from the data file)
    length = "0.30 m"
    diameter = "1.5 in"
    porosity = "0.19"
    permeability = "500 mD"
    swi = "0.28"
    [experiment.fluids]                  # optional: VIS1, VIS2 (viscosity), C50, C60 (meq/ml)
    VIS2 = "13.8 cP"
    [experiment.measurement]             # optional: NoiseModel fields, in the units their names state
    dead_volume_ml = 0.5
"""

from __future__ import annotations

from dataclasses import fields

from spflow.synthetic.noise_model import NoiseModel

__all__ = ["VERSION", "ROLES", "TOP_KEYS", "PARAMETER_KEYS", "EXPERIMENT_KEYS", "CORE_KEYS", "RATE_ATTR",
           "FLUID_KEYS", "MEASUREMENT_KEYS", "MEASUREMENT_UNITS", "FROM_DATA", "EXPERIMENT_PARAMS"]

VERSION = 1
#: what an experiment is for: trains the proxy and calibrations / checks predictions / is only predicted
ROLES = ("calibration", "heldout", "predict")
TOP_KEYS = ("version", "parameters", "effects", "experiment")
PARAMETER_KEYS = ("calibrated", "fixed")
EXPERIMENT_KEYS = ("name", "role", "data", "core", "rate", "schedule", "fluids", "measurement")
#: [experiment.core] key -> (coreflood attr of spflow.io.metadata, quantity kind of spflow.io.quantities)
CORE_KEYS = {"length": ("core_length_m", "length"), "diameter": ("core_diameter_m", "length"),
             "porosity": ("porosity", "fraction"), "permeability": ("permeability_md", "permeability"),
             "swi": ("swi", "fraction")}
#: the coreflood attr of an experiment's ``rate`` (quantity kind "rate")
RATE_ATTR = "qinj_ml_min"
#: [experiment.fluids] key (forward-model name) -> quantity kind; a missing key takes the model default (recorded)
FLUID_KEYS = {"VIS1": "viscosity", "VIS2": "viscosity", "C50": "ion_concentration", "C60": "ion_concentration"}
#: [experiment.measurement] keys: the NoiseModel fields; a missing one takes the NoiseModel default (recorded)
MEASUREMENT_KEYS = tuple(f.name for f in fields(NoiseModel))
#: measurement field -> its unit (the field names state it too)
MEASUREMENT_UNITS = {name: NoiseModel().to_attrs()[f"noise_{name}_units"] for name in MEASUREMENT_KEYS}
#: the ``schedule`` value meaning "the data file's own schedule" (also what a missing ``schedule`` means)
FROM_DATA = "from data"
#: forward-model parameters an experiment sets itself (core and rate); they may not be [parameters.fixed]
EXPERIMENT_PARAMS = ("LENGTH", "DIAMETER", "PORO", "PERM", "SWI", "QINJ")
