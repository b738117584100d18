"""Read an injection schedule (thesis Table 2.5 style) from a TOML file.

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

import tomllib
from pathlib import Path

from spflow.plugins.forward.schedule import Schedule, as_schedule

__all__ = ["read_schedule_file"]


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
