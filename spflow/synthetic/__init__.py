"""Synthetic corefloods: a lab measurement model applied to forward simulations (see ``docs/data.md``).

``make_coreflood`` is the public generator; the measurement chain's parts live one per module:
:mod:`.noise_model` (``NoiseModel``), :mod:`.transducer`, :mod:`.dead_volume`, :mod:`.fraction_collector`,
:mod:`.core_volumes` and :mod:`.measurement` (which chains them).
"""

from .measurement import measure
from .noise_model import NoiseModel
from .twin import make_coreflood, write_twins

__all__ = ["NoiseModel", "make_coreflood", "measure", "write_twins"]
