"""Reading coreflood data: ``load_coreflood`` (bundled names, netCDF, CSV) and TOML schedule files.

The common format is defined in :mod:`spflow.io.format`; see ``docs/data.md``.
"""

from .coreflood import load_coreflood
from .schedule_file import read_schedule_file

__all__ = ["load_coreflood", "read_schedule_file"]
