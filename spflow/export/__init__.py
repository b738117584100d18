"""Export a calibrated spflow coreflood model to other simulators (OPM Flow), and compare their results.

Modules: ``opm_mechanisms`` (what OPM Flow can and cannot express), ``opm_tables`` (the property tables),
``opm_deck`` (the ECLIPSE deck), ``opm_time_steps`` (the cap on OPM's time steps), ``opm_model`` (the model a deck
is written of -- a study's experiment, a parameter file, a calibration's best point or a posterior sample -- and
where each value comes from; :func:`export_opm`), ``eclipse_summary`` (reader of the binary summary files),
``opm_run`` (run ``flow`` and convert its summary to the coreflood format), ``opm_compare`` (figure and table beside
spflow's curves), ``command`` (``spflow export opm`` / ``spflow compare opm``).
"""

from spflow.core.lazy_exports import lazy_exports

#: Imported on first use: the deck writer reads the simulator's physics (numba), which ``spflow export --help`` and
#: the CLI's other verbs must not load.
__all__ = ["export_opm"]
__getattr__, __dir__ = lazy_exports(__name__, {"export_opm": ".opm_model"})
