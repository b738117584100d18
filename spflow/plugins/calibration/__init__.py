"""Calibration stages (NSGA-II, MCMC) and the data they share: observations aligned with surrogate outputs."""
