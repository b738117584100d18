"""The SP coreflood forward model: a 1-D UTCHEM-style IMPES/TVD simulator (``simulate``), its parameter catalogue
(``parameters``), injection schedules (``schedule``), switchable effects (``effects``) and property kernels
(``physics``). See ``docs/forward_model.md``.
"""

from .numba_cache import invalidate_stale_cache

invalidate_stale_cache()  # before any numba function of the forward model loads its on-disk cache
