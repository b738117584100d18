"""Read and write an injection schedule (thesis Table 2.5 style) as a TOML file.

Format::

    name = "my_flood"            # optional
    [[slugs]]
    name = "IWF"                 # optional
    pv = 1.45                    # slug size, PV (> 0)
    salinity_ppm = 9400          # TDS, ppm
    surfactant_ppm = 0           # optional, ppm
    polymer_ppm = 0              # optional, ppm
    rate_ml_min = 0.5            # optional, ml/min (default: the run's QINJ); PV stays the time axis

Every error is a ``ValueError`` naming the file (and the slug and field, from the schedule's own validation).
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

from spflow.plugins.forward.schedule import Schedule, as_schedule

__all__ = ["read_schedule_file", "schedule_toml", "write_schedule_file"]


def read_schedule_file(path) -> Schedule:
    """The :class:`Schedule` described by the TOML file ``path``."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"schedule file {str(path)!r}: no such file")
    try:
        with open(path, "rb") as fh:
            table = tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"schedule file {str(path)!r}: invalid TOML: {exc}") from None
    unknown = sorted(set(table) - {"name", "slugs"})
    if unknown:
        raise ValueError(f"schedule file {str(path)!r}: unknown key(s) {unknown}; allowed keys ['name', 'slugs']")
    if "slugs" not in table:
        raise ValueError(f"schedule file {str(path)!r}: missing [[slugs]] tables")
    try:
        return as_schedule({"name": table.get("name", path.stem), "slugs": table["slugs"]})
    except ValueError as exc:
        raise ValueError(f"schedule file {str(path)!r}: {exc}") from None


def _toml_value(value) -> str:
    if isinstance(value, str):
        return json.dumps(value)  # a JSON string is a valid TOML basic string
    return repr(float(value))


def schedule_toml(schedule) -> str:
    """The TOML text of ``schedule`` (anything ``as_schedule`` accepts) in the format above; ``rate_ml_min`` is
    written only for slugs that set their own rate. :func:`read_schedule_file` reads it back unchanged."""
    sched = as_schedule(schedule)
    lines = [f"name = {_toml_value(sched.name)}"]
    for s in sched.slugs:
        lines += ["", "[[slugs]]", f"name = {_toml_value(s.name)}"]
        fields = ("pv", "salinity_ppm", "surfactant_ppm", "polymer_ppm") + (() if s.rate_ml_min is None
                                                                             else ("rate_ml_min",))
        lines += [f"{f} = {_toml_value(getattr(s, f))}" for f in fields]
    return "\n".join(lines) + "\n"


def write_schedule_file(schedule, path) -> Path:
    """Write ``schedule`` as a TOML schedule file (:func:`schedule_toml`) to ``path``; returns the path."""
    path = Path(path)
    path.write_text(schedule_toml(schedule))
    return path
