"""Example third-party spflow plugin (see README.md): the ``breakthrough`` stage and the ``wettability_alteration``
effect, registered by :mod:`spflow_example.plugin`."""
