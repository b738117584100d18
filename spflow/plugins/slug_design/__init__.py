"""Slug-size design under uncertainty (thesis §4.7): NPV economics and Bayesian global optimisation with EEIHV."""
