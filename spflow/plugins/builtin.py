"""The built-in plugin: registers spflow's own stages and effects through the public hooks."""

from __future__ import annotations

from spflow.core.hookspecs import hookimpl


@hookimpl
def spflow_register_stages(register):
    from spflow.plugins.data import LoadNetCDF

    register(LoadNetCDF)
