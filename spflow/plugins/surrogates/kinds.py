"""Imports every built-in surrogate kind so that :func:`~.contract.load_surrogate` can rebuild it by name."""

from spflow.plugins.surrogates import gp_model, pce_model, pck_model  # noqa: F401
