"""Surrogates (PCE, PC-Kriging, GP) behind one contract: :mod:`.contract`."""
