"""Tests of the forward model (spflow.plugins.forward)."""
