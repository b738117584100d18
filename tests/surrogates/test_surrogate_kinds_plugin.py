"""Surrogate kinds are plugins like stages and effects: the built-ins come through the hook, a plugin's kind is
rebuilt by ``load_surrogate`` wherever spflow loads a stored surrogate, and a kind registered twice or an unknown kind
is an error naming what is registered."""

import numpy as np
import pytest

from spflow.core.errors import PluginError, SchemaError
from spflow.core.plugins import get_registry
from spflow.plugins.surrogates.contract import Surrogate, load_surrogate, surrogate_kinds
from spflow.plugins.surrogates.outputs import OutputIndex
from spflow.plugins.surrogates.pce_model import PCE
from surrogate_kind_plugin import surrogate_kinds_registered


class Plane(Surrogate):
    """y = c + g . x, no variance."""

    kind = "test_plane"

    def __init__(self, names, lower, upper, outputs, c, g):
        super().__init__(names, lower, upper, outputs)
        self.c, self.g = float(c), np.asarray(g, dtype=float)

    def _predict(self, x):
        mean = (self.c + x @ self.g)[:, None]
        return mean, np.zeros_like(mean)

    def to_dataset(self):
        return self._dataset({"c": ((), self.c, {"units": "1"}), "g": ("param", self.g, {"units": "1"})})

    @classmethod
    def from_dataset(cls, ds):
        return cls(**cls._common(ds), c=float(ds["c"]), g=ds["g"].values)


def _plane():
    outputs = OutputIndex(np.array(["y"]), np.array(["E1"]), np.array([1.0]), {"y": "1"})
    return Plane(["a", "b"], [0.0, 0.0], [1.0, 2.0], outputs, 0.5, [2.0, -1.0])


def test_the_builtin_kinds_come_through_the_hook():
    assert {"pce", "gp", "pck"} <= set(surrogate_kinds())
    assert get_registry().providers["surrogate:pce"] == "spflow.plugins.surrogates.pce_model"


def test_a_plugins_kind_round_trips_through_load_surrogate():
    stored = _plane().to_dataset()
    with pytest.raises(SchemaError, match="unknown surrogate kind 'test_plane'.*'pce'"):
        load_surrogate(stored)
    with surrogate_kinds_registered(Plane, name="plane_plugin"):
        assert "test_plane" in surrogate_kinds()
        again = load_surrogate(stored)
        x = np.array([[0.2, 1.5], [1.0, 0.0]])
        assert np.allclose(again.predict(x)[0][:, 0], 0.5 + 2.0 * x[:, 0] - x[:, 1])
    assert "test_plane" not in surrogate_kinds()


def test_a_kind_registered_twice_is_refused_naming_both_providers():
    class OtherPCE(PCE):
        kind = "pce"

    with surrogate_kinds_registered(OtherPCE, name="second_pce"):
        with pytest.raises(PluginError, match="surrogate kind 'pce' registered twice"):
            get_registry()


def test_a_class_without_a_kind_is_refused():
    class NoKind(Plane):
        kind = ""

    with surrogate_kinds_registered(NoKind, name="no_kind"):
        with pytest.raises(PluginError, match="non-empty class attribute 'kind'"):
            get_registry()


def test_spflow_list_shows_the_kinds(capsys):
    from spflow.cli import main

    assert main(["list", "surrogates"]) == 0
    out = capsys.readouterr().out
    assert "pce (from spflow.plugins.surrogates.pce_model)" in out and "pck" in out and "gp" in out
