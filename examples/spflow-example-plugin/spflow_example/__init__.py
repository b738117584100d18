"""Example third-party spflow plugin (see README.md): the ``breakthrough`` stage and the ``wettability_alteration``
effect, registered by :mod:`spflow_example.plugin`, and the ``breakthrough_scan`` pipeline
(:mod:`spflow_example.breakthrough_pipeline`)."""
