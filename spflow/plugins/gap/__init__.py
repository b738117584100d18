"""Sim-to-real gap diagnosis (``diagnose`` stage, ``spflow diagnose``): where a calibrated base model misses, which
catalogue effect explains the miss, and how far the gap shrinks once it is added. See ``docs/gap.md``.

One concept per module: ``base_model`` (what is calibrated), ``catalogue`` (candidate effects), ``observed`` (data
and measurement model), ``error_model`` (AR(1) whitening), ``layout`` (observation vectors), ``prediction`` (the
forward model through the measurement chain), ``least_squares`` / ``base_calibration`` (calibration),
``localisation`` and ``signatures`` (where), ``fingerprints`` and ``candidates`` (which), ``predictive_scores`` and
``verdict`` (decision), ``quantification`` (how far), ``diagnosis`` (the procedure), ``report`` / ``figures``
(output), ``stage`` and ``command`` (entry points); ``design_space``, ``next_experiment``, ``proposal`` and
``design_check`` (the coreflood that would separate ambiguous candidates, ``docs/next_experiment.md``).
"""
