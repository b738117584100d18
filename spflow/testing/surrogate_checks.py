"""``check_surrogate``: the conformance checks of a surrogate kind (the contract of
``spflow/plugins/surrogates/contract.py``, docs/surrogates.md), on a small smooth problem: three outputs of two
parameters on the box [0, 1] x [1, 3], fitted on a seeded Latin hypercube of 12 points.

``declaration``
    a :class:`~spflow.plugins.surrogates.contract.Surrogate` subclass with a non-empty ``kind``, registered under it
    (hook ``spflow_register_surrogate_kinds``), so that ``load_surrogate`` can rebuild it.
``fit``
    the fitter (the kind's ``fit(names, lower, upper, outputs, x, y, **options)`` classmethod, or ``fit=`` given)
    returns an instance of the kind with the names and box it was given.
``predict_shapes``
    ``predict`` gives a finite mean and a finite, non-negative variance of shape (n, n_output) for 1 and 7 points;
    ``predict_dataset`` has dims (``sample``, ``output``).
``training_points``
    at the training points the mean reproduces the data within the error the kind reports: the mean squared residual
    of each output is at most its mean predicted variance (a PCE's LOO error, Eq. 3.8; a Kriging variance, which
    its nugget makes non-zero there); for an interpolating kind, given ``interpolation_tolerance``, every residual
    is also at most that fraction of the output's spread.
``determinism``
    a second fit on the same data gives bit-identical predictions and an identical stored Dataset.
``purity``
    fitting and predicting leave the caller's arrays unchanged.
``round_trip``
    ``to_dataset`` matches the ``SURROGATE`` schema with ``attrs["surrogate"] = kind``; ``load_surrogate`` of it, and
    of it written and read by the cache's netCDF store, predicts bit-identically.
``nan_points``
    ``predict`` refuses a NaN or a wrong-width point with a spflow error (:class:`ParameterError`).
``nan_training``
    a NaN among the training outputs is refused with a spflow error, not fitted into numbers or a raw traceback.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from scipy.stats import qmc

from spflow.core.errors import SpflowError
from spflow.core.plugins import get_registry
from spflow.plugins.surrogates.contract import SURROGATE, Surrogate, load_surrogate
from spflow.plugins.surrogates.outputs import OutputIndex

from .checklist import Broken, Check, Checklist, ConformanceReport
from .datasets import cache_round_trip, differences

__all__ = ["check_surrogate", "SURROGATE_CHECKS", "SmoothProblem"]

SURROGATE_CHECKS = {c.name: c for c in (
    Check("declaration", "a Surrogate subclass with a non-empty 'kind', registered under that kind",
          "subclass spflow.plugins.surrogates.contract.Surrogate, set kind = '<unique name>' and register the class "
          "in a spflow_register_surrogate_kinds hook (docs/plugins.md)"),
    Check("fit", "the fitter returns an instance of the kind with the names and box it was given",
          "give the class a classmethod fit(names, lower, upper, outputs, x, y, **options) returning cls(...), or "
          "pass fit=<callable> to check_surrogate"),
    Check("predict_shapes", "predict(x) returns a finite mean and a finite non-negative variance, each "
          "(n, n_output)", "return (mean, variance) arrays of shape (len(x), len(outputs)) from _predict"),
    Check("training_points", "at the training points the mean reproduces the data (interpolating kinds) or stays "
          "within the error variance the kind reports (regression kinds)",
          "check the fit's scaling of x and y; report as variance an honest error estimate (e.g. the LOO error)"),
    Check("determinism", "two fits on the same data give identical predictions and stored Datasets",
          "seed every random start (optimiser restarts, subsampling) from a 'seed' option"),
    Check("purity", "fit and predict leave the caller's arrays unchanged",
          "copy arrays before scaling or sorting them in place (np.array(x, dtype=float) copies)"),
    Check("round_trip", "to_dataset() matches the SURROGATE schema and load_surrogate rebuilds a surrogate predicting "
          "bit-identically, also after the cache's netCDF write and read",
          "store every array the prediction needs in to_dataset (via self._dataset) and read them back in "
          "from_dataset (cls._common(ds) for the shared part); attrs of types str/int/float only"),
    Check("nan_points", "predict refuses a NaN or a wrong-width point with a spflow error",
          "call self.check_points(x) first (Surrogate.predict does) when overriding predict"),
    Check("nan_training", "a NaN in the training data is refused with a spflow error",
          "check x and y are finite before fitting and raise ParameterError naming the kind"),
)}


class SmoothProblem:
    """Three smooth outputs of two parameters: a plane, a product and a curved one, on [0, 1] x [1, 3]."""

    names = ["a", "b"]
    lower = np.array([0.0, 1.0])
    upper = np.array([1.0, 3.0])
    outputs = OutputIndex(np.array(["y", "y", "y"]), np.array(["T1", "T1", "T1"]), np.array([0.1, 0.2, 0.3]),
                          {"y": "1"})

    @staticmethod
    def response(x: np.ndarray) -> np.ndarray:
        a, b = x[:, 0], x[:, 1]
        return np.column_stack([1.0 + 2.0 * a - b, a * b, np.sin(2.0 * a) + 0.25 * b**2])

    def points(self, n: int, seed: int) -> np.ndarray:
        return qmc.scale(qmc.LatinHypercube(d=2, seed=seed).random(n), self.lower, self.upper)


class _SurrogateRun:
    def __init__(self, cls: type, fitter: Callable[..., Any], options: Mapping[str, Any], points: int,
                 tolerance: float | None):
        self.cls, self.fitter, self.options, self.tolerance = cls, fitter, dict(options), tolerance
        self.problem = SmoothProblem()
        self.x = self.problem.points(points, seed=0)
        self.y = self.problem.response(self.x)
        self.probe = self.problem.points(7, seed=1)
        self.model: Surrogate | None = None

    def fit(self, x: np.ndarray | None = None, y: np.ndarray | None = None) -> Surrogate:
        p = self.problem
        return self.fitter(list(p.names), p.lower.copy(), p.upper.copy(), p.outputs,
                           (self.x if x is None else x).copy(), (self.y if y is None else y).copy(), **self.options)

    def first_fit(self) -> None:
        model = self.fit()
        if not isinstance(model, self.cls):
            raise Broken(f"the fitter returned a {type(model).__name__}, not a {self.cls.__name__}")
        p = self.problem
        if list(model.names) != p.names or not (np.array_equal(model.lower, p.lower)
                                                and np.array_equal(model.upper, p.upper)):
            raise Broken(f"the fitted surrogate has names {model.names}, box {model.lower}-{model.upper}; given "
                         f"{p.names}, {p.lower}-{p.upper}")
        self.model = model

    def predict_shapes(self) -> None:
        m = len(self.problem.outputs)
        for x in (self.probe[:1], self.probe):
            mean, var = self.model.predict(x)
            if np.shape(mean) != (len(x), m) or np.shape(var) != (len(x), m):
                raise Broken(f"for {len(x)} points: mean {np.shape(mean)}, variance {np.shape(var)}; expected "
                             f"({len(x)}, {m}) each")
            if not (np.isfinite(mean).all() and np.isfinite(var).all() and (var >= 0).all()):
                raise Broken(f"for {len(x)} points: non-finite mean or variance, or a negative variance")
        ds = self.model.predict_dataset(self.probe)
        if ds["mean"].dims != ("sample", "output") or ds["variance"].dims != ("sample", "output"):
            raise Broken(f"predict_dataset dims {ds['mean'].dims}, expected ('sample', 'output')")

    def training_points(self) -> None:
        mean, var = self.model.predict(self.x)
        spread = self.y.std(axis=0)
        mse, reported = np.mean((mean - self.y) ** 2, axis=0), np.mean(var, axis=0)
        over = mse > reported * (1 + 1e-9) + 1e-12 * spread**2
        if over.any():
            k = int(np.flatnonzero(over)[0])
            raise Broken(f"output {k}: mean squared residual at the training points {mse[k]:.3g} exceeds the mean "
                         f"predicted (error) variance {reported[k]:.3g}")
        if self.tolerance is not None:
            worst = np.max(np.abs(mean - self.y), axis=0) / spread
            if (worst > self.tolerance).any():
                raise Broken(f"an interpolating kind misses its training data by up to {worst.max():.3g} of the "
                             f"outputs' spread (allowed {self.tolerance:g})")

    def determinism(self) -> None:
        again = self.fit()
        if not np.array_equal(again.predict(self.probe)[0], self.model.predict(self.probe)[0]):
            raise Broken("a second fit predicts differently")
        found = differences(self.model.to_dataset(), again.to_dataset())
        if found:
            raise Broken("a second fit stores a different Dataset: " + "; ".join(found))

    def purity(self) -> None:
        x, y, probe = self.x.copy(), self.y.copy(), self.probe.copy()
        p = self.problem
        lower, upper = p.lower.copy(), p.upper.copy()
        self.fitter(list(p.names), lower, upper, p.outputs, x, y, **self.options).predict(probe)
        changed = [n for n, a, b in (("x", x, self.x), ("y", y, self.y), ("points", probe, self.probe),
                                     ("lower", lower, p.lower), ("upper", upper, p.upper)) if not np.array_equal(a, b)]
        if changed:
            raise Broken(f"the caller's {changed} changed")

    def round_trip(self) -> None:
        ds = self.model.to_dataset()
        try:
            SURROGATE.validate(ds, stage=f"surrogate kind {self.cls.kind!r}", port="to_dataset()")
        except SpflowError as exc:
            raise Broken(str(exc)) from None
        if ds.attrs.get("surrogate") != self.cls.kind:
            raise Broken(f"attrs['surrogate'] = {ds.attrs.get('surrogate')!r}, expected {self.cls.kind!r}")
        expected = self.model.predict(self.probe)
        for how, stored in (("load_surrogate(to_dataset())", ds),
                            ("after the cache's netCDF write and read",
                             cache_round_trip(ds, where=f"surrogate kind {self.cls.kind!r}"))):
            back = load_surrogate(stored)
            got = back.predict(self.probe)
            if not (type(back) is self.cls and all(np.array_equal(a, b) for a, b in zip(got, expected))):
                raise Broken(f"{how} gives a {type(back).__name__} predicting differently")

    def nan_points(self) -> None:
        bad = self.probe[:2].copy()
        bad[0, 0] = np.nan
        for what, x in (("a NaN point", bad), ("points of the wrong width", self.probe[:, :1])):
            try:
                self.model.predict(x)
            except SpflowError:
                continue
            except Exception as exc:  # noqa: BLE001 - the finding is that it was not a spflow error
                raise Broken(f"{what} raised {type(exc).__name__}: {exc}") from None
            raise Broken(f"{what} was predicted without an error")

    def nan_training(self) -> None:
        y = self.y.copy()
        y[len(y) // 2, 0] = np.nan
        try:
            model = self.fit(y=y)
        except SpflowError:
            return
        except Exception as exc:  # noqa: BLE001
            raise Broken(f"a NaN training output raised {type(exc).__name__}: {exc}") from None
        if np.isfinite(model.predict(self.probe)[0]).all():
            raise Broken("a NaN training output was fitted into a surrogate predicting finite numbers")
        raise Broken("a NaN training output was accepted (the surrogate predicts NaN)")


def check_surrogate(kind: str | type[Surrogate], *, fit: Callable[..., Surrogate] | None = None,
                    options: Mapping[str, Any] | None = None, interpolation_tolerance: float | None = None,
                    points: int = 12) -> ConformanceReport:
    """Run the surrogate conformance checks (module docstring) on ``kind`` (a registered kind's name or its class).

    ``fit(names, lower, upper, outputs, x, y, **options)`` builds a surrogate (default: the class's ``fit``). At the
    training points the mean must stay within the variance the kind reports, and, for an interpolating kind given
    ``interpolation_tolerance``, within that fraction of each output's spread; ``points`` is the training-set size. Returns the report of passed checks or raises one
    :class:`~.checklist.ConformanceError` listing every failed check.
    """
    name = kind if isinstance(kind, str) else getattr(kind, "kind", repr(kind))
    checks = Checklist(f"check_surrogate({name!r})")
    c = SURROGATE_CHECKS
    resolved: list[type] = []

    def declaration() -> None:
        cls = get_registry().surrogate_kind(kind) if isinstance(kind, str) else kind
        if not (isinstance(cls, type) and issubclass(cls, Surrogate)):
            raise Broken(f"{cls!r} is not a Surrogate subclass")
        if not (isinstance(cls.kind, str) and cls.kind):
            raise Broken(f"kind = {cls.kind!r}")
        registered = get_registry().surrogate_kinds.get(cls.kind)
        if registered is not cls:
            raise Broken(f"kind {cls.kind!r} is registered as {registered!r}, not {cls.__qualname__}")
        resolved.append(cls)

    if not checks.run(c["declaration"], declaration):
        return checks.finish()
    cls = resolved[0]
    fitter = fit if fit is not None else getattr(cls, "fit", None)
    if not callable(fitter):
        checks.run(c["fit"], _no_fitter, cls)
        return checks.finish()
    run = _SurrogateRun(cls, fitter, options or {}, points, interpolation_tolerance)
    checks.run(c["fit"], run.first_fit)
    for name in ("predict_shapes", "training_points", "determinism", "purity", "round_trip", "nan_points"):
        checks.run(c[name], getattr(run, name), needs=("fit",))
    checks.run(c["nan_training"], run.nan_training)
    return checks.finish()


def _no_fitter(cls: type) -> None:
    raise Broken(f"{cls.__qualname__} has no fit classmethod and no fit= was given")
