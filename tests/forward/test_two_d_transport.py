"""Cross-row (y) advective fluxes of the 2-D transport: each y face takes the TVD (van Leer, Lax-Wendroff factor)
face value of its own upwind stencil, for upward and downward flow, against the van Leer formula evaluated here on a
single-phase water column carrying a non-monotone salinity profile (the anion flux is then the limited face
salinity); first order at the first interior face from the wall the flow comes from, and with ``tvd=False``."""

import numpy as np
import pytest

from spflow.plugins.forward import kernel as KR
from spflow.plugins.forward import kernel_inputs as K
from spflow.plugins.forward import state_layout as L
from spflow.plugins.forward import transport as T
from spflow.plugins.forward.effects import default_registry
from spflow.plugins.forward.parameters import resolve_params
from spflow.plugins.forward.two_d.transport2d import advective_fluxes_2d


def van_leer(qm, q0, qp, w):
    dm, dp = q0 - qm, qp - q0
    return q0 + w * dm * dp / (dm + dp) if dm * dp > 0.0 else q0


@pytest.mark.parametrize("tvd", [True, False])
def test_y_faces_take_the_limited_value_of_their_upwind_stencil(tvd):
    nx, ny = 3, 9
    n = nx * ny
    prm = K.build_kernel_params(resolve_params({}), default_registry().resolve({}))
    y = np.arange(ny)
    salinity = np.stack([0.2 + 0.1 * np.sin(0.7 * y + ix) + 0.01 * y ** 2 for ix in range(nx)], axis=1)  # [ny, nx]
    st = np.zeros((L.NST, n))
    pr = np.zeros((L.NPR, n))
    st[L.M1] = 1.0
    st[L.RK] = 1.0
    st[L.M5] = salinity.ravel()
    assert KR.update_properties(st, pr, prm, n, 0.0, np.zeros(KR.N_INFO), 0.0) == L.OK
    assert np.all(pr[L.F1] == 1.0) and np.all(pr[L.V1] == 1.0)  # water only: anion flux = face salinity
    faces = np.arange(1, ny)
    vy = np.zeros((ny + 1, nx))
    vy[1:-1, 0] = 0.5 + 0.1 * faces  # upward
    vy[1:-1, 1] = -(0.3 + 0.05 * faces)  # downward
    vy[1:-1, 2] = np.where(faces < 5, 0.4, -0.6)  # converging on row 4/5 face
    ux = np.zeros((ny, nx + 1))
    fx = np.zeros((T.NFLUX, ny, nx + 1))
    gy = np.zeros((T.NFLUX, ny + 1, nx))
    lam_y = 0.2
    advective_fluxes_2d(pr, nx, ny, ux, vy, tvd, 0.1, lam_y, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, fx, gy)
    for ix in range(nx):
        c = salinity[:, ix]
        w = 1.0 - lam_y * np.sum(np.abs(vy[:, ix])) / (ny + 1)  # carrier velocity 1
        for j in faces:
            if vy[j, ix] >= 0.0:
                i = j - 1
                expected = c[i] if (not tvd or i == 0) else van_leer(c[i - 1], c[i], c[i + 1], w)
            else:
                i = j
                expected = c[i] if (not tvd or i == ny - 1) else van_leer(c[i + 1], c[i], c[i - 1], w)
            assert gy[T.FW, j, ix] == pytest.approx(1.0, abs=1e-15)
            assert gy[T.FA, j, ix] == pytest.approx(expected, rel=1e-14), (ix, j)
    upwind = np.where(vy[1:-1] >= 0.0, salinity[:-1], salinity[1:])
    if tvd:  # the second-order values differ from upwind (the test can tell the schemes apart)
        assert np.max(np.abs(gy[T.FA, 1:-1] - upwind)) > 1e-3
    else:
        assert np.array_equal(gy[T.FA, 1:-1], upwind)
