"""Export a calibrated spflow coreflood model to other simulators (OPM Flow), and compare their results.

Modules: ``opm_mechanisms`` (what OPM Flow can and cannot express), ``opm_tables`` (the property tables),
``opm_deck`` (the ECLIPSE deck), ``eclipse_summary`` (reader of the binary summary files), ``opm_run`` (run
``flow`` and convert its summary to the coreflood format), ``opm_compare`` (figure and table beside spflow's
curves), ``command`` (``spflow export opm`` / ``spflow compare opm``).
"""
