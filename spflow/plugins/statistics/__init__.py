"""Summary statistics of ensembles of responses."""
