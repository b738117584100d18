"""A third-party effect contributed through the ``spflow_register_effects`` hook is listed and applied by
``simulate``: its parameter transform must equal running the base model with the transformed parameters directly."""

import numpy as np
import pytest

import spflow
from spflow.plugins.forward.effects import Effect

VISCOUS_OIL = Effect(
    "viscous_oil",
    "oil viscosity raised by (1 + strength)",
    default_strength=0.0,
    lower=0.0,
    upper=5.0,
    transform_params=lambda p, s: dict(p, VIS2=p["VIS2"] * (1.0 + s)),
    transform_output=lambda ds, s: ds.assign_attrs(viscous_oil_strength=s),
)


class OilPlugin:
    @spflow.hookimpl
    def spflow_register_effects(self, register):
        register(VISCOUS_OIL)


@pytest.fixture
def oil_plugin():
    spflow.register_plugin(OilPlugin(), name="viscous_oil_plugin")
    yield
    spflow.unregister_plugin("viscous_oil_plugin")


def test_third_party_effect_is_registered_and_applied(oil_plugin):
    assert spflow.get_registry().effects["viscous_oil"] is VISCOUS_OIL
    with_effect = spflow.simulate("BCF1", {"VIS2": 10.0}, cells=30, pv_step=0.1, effects={"viscous_oil": 1.0})
    direct = spflow.simulate("BCF1", {"VIS2": 20.0}, cells=30, pv_step=0.1)
    for name in ["dp", "oil_cut", "recovery"]:
        np.testing.assert_array_equal(with_effect[name].values, direct[name].values)
    assert with_effect.attrs["viscous_oil_strength"] == 1.0
    off = spflow.simulate("BCF1", {"VIS2": 10.0}, cells=30, pv_step=0.1)
    assert not np.array_equal(off["dp"].values, with_effect["dp"].values)


def test_third_party_effect_strength_is_validated(oil_plugin):
    with pytest.raises(spflow.ParameterError, match=r"effect 'viscous_oil' strength 9 is out of range; allowed \[0, 5\]"):
        spflow.simulate("BCF1", cells=30, effects={"viscous_oil": 9})


def test_unknown_effect_is_named():
    with pytest.raises(spflow.ParameterError, match="unknown effect 'viscous_oil'"):
        spflow.simulate("BCF1", cells=30, effects={"viscous_oil": 1.0})
