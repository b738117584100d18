"""Synthetic corefloods: a lab measurement model applied to forward simulations (see ``docs/data.md``).

``make_coreflood`` is the public generator; the measurement chain's parts live one per module:
:mod:`.noise_model` (``NoiseModel``), :mod:`.transducer`, :mod:`.dead_volume`, :mod:`.fraction_collector`,
:mod:`.core_volumes` and :mod:`.measurement` (which chains them).
"""

from spflow.core.lazy_exports import lazy_exports

#: Imported on first use: ``make_coreflood`` runs the simulator (numba), which readers of corefloods
#: (:mod:`spflow.io`, importing :class:`NoiseModel`) must not load.
_EXPORTS = {"NoiseModel": ".noise_model", "make_coreflood": ".twin", "measure": ".measurement",
            "write_twins": ".twin"}

__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
