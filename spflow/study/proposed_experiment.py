"""A proposed coreflood as an experiment of a study file: the next experiment of a gap diagnosis
(:mod:`spflow.plugins.gap.next_experiment`) in the study schema (:mod:`spflow.study.schema`).

:func:`study_experiment_toml` writes one ``[[experiment]]`` table with role ``predict`` (no data yet): the design's
schedule as a TOML schedule file next to the study, and the core, base rate and measurement chain of the coreflood
the design was ranked on. Append it to the study file and ``spflow check`` it. A core value or rate the reference
coreflood does not state is written as a commented ``FILL IN`` line and returned in the list of fields to fill in:
no default is assumed for it.
"""

from __future__ import annotations

import json
from collections.abc import Mapping

from spflow.io.metadata import CORE_ATTRS, core_unit
from spflow.synthetic.noise_model import NoiseModel

from .schema import CORE_KEYS, MEASUREMENT_KEYS, RATE_ATTR

__all__ = ["study_experiment_toml"]


def study_experiment_toml(name: str, schedule_file: str, core: Mapping[str, float], measurement: NoiseModel,
                          reference: str = "") -> tuple[str, list[str]]:
    """``(TOML text, fields to fill in)`` of a predict-only study experiment ``name`` injecting the schedule file
    ``schedule_file`` (a path relative to the study file) on a core described by forward-model parameters ``core``
    (``LENGTH`` m, ``DIAMETER`` m, ``PORO``, ``PERM`` mD, ``SWI``, ``QINJ`` ml/min: e.g. a gap ``Experiment``'s
    ``core``) with the measurement chain ``measurement``; ``reference`` names that coreflood in a comment."""
    lines = [f"# The proposed next coreflood (spflow gap diagnosis){f', on the core of {reference!r}' if reference else ''}",
             "[[experiment]]", f"name = {json.dumps(name)}", 'role = "predict"', f"schedule = {json.dumps(schedule_file)}"]
    missing = []
    rate = core.get(CORE_ATTRS[RATE_ATTR])
    if rate is None:
        lines.append('# rate = "<number> ml/min"  # FILL IN: the reference coreflood states no rate')
        missing.append("rate")
    else:
        lines.append(f'rate = "{float(rate)!r} ml/min"  # the base rate; slugs with rate_ml_min set their own')
    lines.append("[experiment.core]")
    for key, (attr, kind) in CORE_KEYS.items():
        value = core.get(CORE_ATTRS[attr])
        unit = "" if kind == "fraction" else f" {core_unit(attr)}"
        if value is None:
            lines.append(f'# {key} = "<number>{unit}"  # FILL IN: the reference coreflood does not state it')
            missing.append(f"core.{key}")
        else:
            lines.append(f'{key} = "{float(value)!r}{unit}"')
    lines.append("[experiment.measurement]  # the reference coreflood's measurement chain")
    lines += [f"{key} = {float(getattr(measurement, key))!r}" for key in MEASUREMENT_KEYS]
    return "\n".join(lines) + "\n", missing
