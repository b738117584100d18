"""Two-dimensional (x-y) heterogeneous-core version of the forward model (thesis sec. 1.8, Fig. 1.9).

Entry point ``simulate2d`` (also reached through ``spflow.simulate(..., cells=(nx, ny), permeability=...)``);
``permeability_field`` generates the seeded log-normal permeability field. See ``docs/two_d.md``.
"""

from .permeability_field import permeability_field, sample_variogram
from .simulate2d import simulate2d

__all__ = ["permeability_field", "sample_variogram", "simulate2d"]
