"""Bad 2-D input raises a ValueError naming the field and its allowed range, before any work."""

import numpy as np
import pytest
import xarray as xr

from spflow.plugins.forward.simulate import simulate
from spflow.plugins.forward.two_d.simulate2d import simulate2d

WATER = [{"pv": 0.1, "salinity_ppm": 9400.0}]


@pytest.mark.parametrize("cells,match", [((2, 4), r"cells\[0\] \(nx\)"), ((10, 0), r"cells\[1\] \(ny\)"),
                                         ((10, 2.5), r"cells\[1\]"), ((10, 4, 2), r"pair \(nx, ny\)"),
                                         ((True, 4), r"cells\[0\]"), ((2000, 2000), "nx \\* ny")])
def test_bad_cells(cells, match):
    with pytest.raises(ValueError, match=match):
        simulate(WATER, cells=cells)


@pytest.mark.parametrize("perm,match", [(np.ones((4, 9)), r"shape \(ny, nx\) = \(4, 10\)"),
                                        (np.full((4, 10), -1.0), "> 0 mD"),
                                        (np.full((4, 10), np.nan), "finite"),
                                        (np.full((4, 10), 1e7), "out of range"),
                                        ("abc", "array of numbers"),
                                        (xr.DataArray(np.ones((10, 4)), dims=("x", "y")), "dims"),
                                        (xr.DataArray(np.ones((4, 10)), dims=("y", "x"), attrs={"units": "m2"}),
                                         "mD")])
def test_bad_permeability(perm, match):
    with pytest.raises(ValueError, match="permeability") as info:
        simulate(WATER, cells=(10, 4), permeability=perm)
    assert info.match(match)


def test_permeability_needs_a_2d_grid():
    with pytest.raises(ValueError, match=r"cells must be a pair \(nx, ny\)"):
        simulate(WATER, cells=10, permeability=np.ones((1, 10)))


@pytest.mark.parametrize("kwargs,match", [({"alpha_t_ratio": 2.0}, "alpha_t_ratio"),
                                          ({"pressure_every": 0}, "pressure_every"),
                                          ({"effects": {"capillary_pressure": 1.0}}, "capillary_pressure"),
                                          ({"cfl": 0.9}, "cfl")])
def test_bad_2d_options(kwargs, match):
    with pytest.raises(ValueError, match=match):
        simulate(WATER, cells=(10, 4), **kwargs)


def test_bad_pressure_solver():
    with pytest.raises(ValueError, match=r"pressure_solver must be one of \('pcg', 'direct'\), got 'lu'"):
        simulate2d(WATER, cells=(10, 4), pressure_solver="lu")
    with pytest.raises(ValueError, match=r"pressure_solver must be one of \('pcg', 'direct'\), got 'lu'"):
        simulate(WATER, cells=(10, 4), pressure_solver="lu")  # the public entry point passes it on
