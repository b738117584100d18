"""``check_stage``: the conformance checks of a :class:`~spflow.core.stage.Stage` (built-in or a plugin's).

The contract (``spflow/core/stage.py``, docs/plugins.md "A stage") as checks, each named in the error when it fails:

``declaration``
    ``name``/``version`` non-empty strings, ``inputs`` a mapping of ports to :class:`DatasetSchema` (or ``None``),
    ``optional_inputs`` among them, ``output`` a schema (or ``None``), ``params`` :class:`Param` declarations whose
    defaults pass their own validation, and every schema well formed (dims tuples of names, dtype kinds numpy kinds,
    units strings).
``construct``
    the class builds with the given parameters; a refusal is a :class:`~spflow.core.errors.ParameterError`.
``params``
    ``stage.params`` holds exactly the declared names: the values the constructor was given, the declared defaults for
    the rest; validating them again changes nothing (they are canonical: the provenance key hashes them).
``inputs``
    the inputs the check was given wire every required port and match the port schemas (a precondition of the run
    checks: a failure here is in the inputs passed to ``check_stage``).
``runs``
    ``run(ctx, **inputs)`` returns a new :class:`xarray.Dataset` (not one of its inputs).
``output_schema``
    the result matches the declared output schema (dims, variables, dtype kinds, units, finiteness).
``output_units``
    every numeric data variable of the result carries a ``units`` attribute (a UDUNITS string).
``purity``
    the inputs are unchanged by the run (values, coordinates and attributes compared bit for bit with a deep copy).
``determinism``
    a second stage built with the same parameters, on fresh copies of the same inputs, returns an identical result
    (seeded randomness only).
``cache_round_trip``
    the result written to the cache's netCDF store and read back is identical (attribute types netCDF can hold, no
    objects, no dtype lost).
``nan_inputs``
    a NaN in a float input the port schema lets through (undeclared, or ``allow_nan``) is rejected with a spflow error
    (:class:`~spflow.core.errors.SpflowError`, e.g. ``ParameterError`` naming the field), propagated into the result,
    or ignored (the result unchanged) — never turned silently into numbers, never a raw numpy/scipy traceback. Ports
    listed in ``nan_as_missing`` document NaN as "not measured": there the stage must run or reject cleanly. It
    compares results with the clean run's, so it needs ``output_schema`` and ``determinism`` to have passed.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np
import xarray as xr

from spflow.core.cf_metadata import has_units_per_element
from spflow.core.errors import SpflowError
from spflow.core.params import Param, validate_params
from spflow.core.schema import DatasetSchema, Variable
from spflow.core.stage import Stage, StageContext

from .checklist import Broken, Check, Checklist, ConformanceReport, NotApplicable
from .datasets import cache_round_trip, differences, float_data_variables, with_nan

__all__ = ["check_stage", "STAGE_CHECKS"]

_NUMPY_KINDS = set("biufcmMOSUV")

STAGE_CHECKS = {c.name: c for c in (
    Check("declaration", "the class declares name, version, inputs, output and params as the Stage contract says",
          "set non-empty string 'name' and 'version', 'inputs' = {port: DatasetSchema or None}, 'output' = "
          "DatasetSchema or None, 'params' = {name: Param} with defaults inside their own bounds/choices"),
    Check("construct", "the stage builds from the params given to check_stage; a refusal is a ParameterError",
          "pass params the stage accepts; refuse bad ones in __init__ with spflow.ParameterError naming the parameter "
          "and the allowed values, never another exception"),
    Check("params", "stage.params equals the constructor's arguments plus the declared defaults, canonical and "
          "JSON-serialisable", "do not change params in __init__ (derive other attributes instead) and let "
          "Stage.__init__ validate them; keep values JSON types (they enter the provenance key)"),
    Check("inputs", "the inputs given to check_stage wire every required port and match the port schemas",
          "pass a Dataset for every port not in optional_inputs, built to the port's DatasetSchema"),
    Check("runs", "run(ctx, **inputs) returns a new xarray.Dataset",
          "return a new Dataset built from the inputs, never one of the input objects or another type"),
    Check("output_schema", "the result matches the declared output schema",
          "make run() produce every declared variable with the declared dims, dtype kind, units and finiteness, or "
          "correct the declaration (allow_nan=True for documented NaN)"),
    Check("output_units", "every numeric data variable of the result has a 'units' attribute (or units per element: "
          "'units_variable' naming a string variable of units along some of its dims, docs/architecture.md)",
          "set attrs['units'] to a UDUNITS string on each numeric variable ('1' for dimensionless)"),
    Check("purity", "run() leaves its inputs unchanged", "work on copies (ds.copy(deep=True)) or build new arrays; "
          "never assign into input arrays or their attrs"),
    Check("determinism", "two runs with the same parameters and inputs give identical results",
          "draw random numbers only from a generator seeded by a 'seed' parameter; no wall-clock times, process ids "
          "or unordered set/dict iteration in the result"),
    Check("cache_round_trip", "the result survives the cache's netCDF write and read unchanged",
          "use attrs of types str/int/float (or lists of them), no Python objects or bools in attrs, dtypes netCDF "
          "stores (no object arrays of mixed types)"),
    Check("nan_inputs", "a NaN in a float input is rejected with a spflow error, propagated, or has no effect — "
          "never silently turned into numbers", "check inputs before any work and raise ParameterError naming the "
          "port, the variable and what is allowed; or propagate NaN and declare allow_nan=True on the output"),
)}


def _schema_problems(where: str, schema: Any) -> list[str]:
    if schema is None:
        return []
    if not isinstance(schema, DatasetSchema):
        return [f"{where} is a {type(schema).__name__}, not a DatasetSchema or None"]
    problems = []
    if not (isinstance(schema.dims, tuple) and all(isinstance(d, str) for d in schema.dims)):
        problems.append(f"{where} dims {schema.dims!r} is not a tuple of names")
    for name, var in schema.variables.items():
        if not isinstance(var, Variable):
            problems.append(f"{where} variable {name!r} is a {type(var).__name__}, not a Variable")
            continue
        if var.dims is not None and not (isinstance(var.dims, tuple) and all(isinstance(d, str) for d in var.dims)):
            problems.append(f"{where} variable {name!r} dims {var.dims!r} is not a tuple of names or None")
        if not (isinstance(var.kind, str) and var.kind and set(var.kind) <= _NUMPY_KINDS):
            problems.append(f"{where} variable {name!r} kind {var.kind!r} is not a string of numpy dtype kinds")
        if var.units is not None and not isinstance(var.units, str):
            problems.append(f"{where} variable {name!r} units {var.units!r} is not a string or None")
    return problems


def _check_declaration(cls: type) -> None:
    problems = []
    if not (isinstance(cls, type) and issubclass(cls, Stage)):
        raise Broken(f"{cls!r} is not a subclass of spflow.Stage")
    for attr in ("name", "version"):
        if not (isinstance(getattr(cls, attr), str) and getattr(cls, attr)):
            problems.append(f"{attr} = {getattr(cls, attr)!r}")
    if not isinstance(cls.inputs, Mapping):
        problems.append(f"inputs is a {type(cls.inputs).__name__}, not a mapping")
    else:
        for port, schema in cls.inputs.items():
            problems += _schema_problems(f"input port {port!r}", schema)
        extra = sorted(set(cls.optional_inputs) - set(cls.inputs))
        if extra:
            problems.append(f"optional_inputs {extra} are not input ports")
    problems += _schema_problems("output", cls.output)
    if not isinstance(cls.params, Mapping):
        problems.append(f"params is a {type(cls.params).__name__}, not a mapping")
    else:
        for name, spec in cls.params.items():
            if not isinstance(spec, Param):
                problems.append(f"param {name!r} is a {type(spec).__name__}, not a Param")
            elif not spec.required:
                try:
                    validate_params(cls.name, {name: spec}, {name: spec.default})
                except SpflowError as exc:
                    problems.append(f"the default of param {name!r} fails its own declaration: {exc}")
    if problems:
        raise Broken("; ".join(problems))


def _plain(value: Any) -> Any:
    """JSON-like form for comparing parameter values (tuples as lists, numpy scalars as Python numbers)."""
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def _check_params(stage: Stage, given: Mapping[str, Any] | None) -> None:
    cls, params = type(stage), dict(stage.params)
    problems = []
    if set(params) != set(cls.params):
        problems.append(f"params has names {sorted(params)}, declared {sorted(cls.params)}")
    for name, spec in cls.params.items():
        if name not in params:
            continue
        if given is not None and name in given:
            if _plain(params[name]) != _plain(given[name]):
                problems.append(f"{name!r} = {params[name]!r}, the constructor was given {given[name]!r}")
        elif given is not None and not spec.required and _plain(params[name]) != _plain(spec.default):
            problems.append(f"{name!r} = {params[name]!r}, its declared default is {spec.default!r}")
    try:
        again = validate_params(cls.name, cls.params, params)
    except SpflowError as exc:
        problems.append(f"validating stage.params again fails: {exc}")
    else:
        if _plain(again) != _plain(params):
            problems.append("validating stage.params again changes them (not canonical)")
    try:
        json.dumps(params, sort_keys=True, allow_nan=False)
    except (TypeError, ValueError) as exc:
        problems.append(f"params are not JSON-serialisable: {exc}")
    if problems:
        raise Broken("; ".join(problems))


def _check_inputs(stage: Stage, inputs: Mapping[str, xr.Dataset]) -> None:
    cls = type(stage)
    problems = []
    unknown = sorted(set(inputs) - set(cls.inputs))
    if unknown:
        problems.append(f"ports {unknown} are not declared (declared: {sorted(cls.inputs)})")
    missing = sorted(set(cls.inputs) - set(cls.optional_inputs) - set(inputs))
    if missing:
        problems.append(f"required ports {missing} have no input")
    for port, ds in inputs.items():
        schema = cls.inputs.get(port)
        if not isinstance(ds, xr.Dataset):
            problems.append(f"port {port!r} got a {type(ds).__name__}, not an xarray.Dataset")
        elif schema is not None:
            try:
                schema.validate(ds, stage=cls.name, port=port)
            except SpflowError as exc:
                problems.append(str(exc))
    if problems:
        raise Broken("; ".join(problems))


class _StageRun:
    """The runs of one stage the checks share: the first result, on deep copies of the inputs."""

    def __init__(self, stage: Stage, inputs: Mapping[str, xr.Dataset]):
        self.stage, self.inputs = stage, dict(inputs)
        self.given: dict[str, xr.Dataset] = {}
        self.result: xr.Dataset | None = None
        self.impure = False

    def context(self) -> StageContext:
        return StageContext(node=f"check_stage[{self.stage.name}]", n_jobs=1, verbose=False)

    def rerun(self) -> Any:
        """A second stage built with the same parameters, on fresh copies of the inputs."""
        copies = {p: ds.copy(deep=True) for p, ds in self.inputs.items()}
        return type(self.stage)(**self.stage.params).run(self.context(), **copies)

    def first(self) -> None:
        self.given = {p: ds.copy(deep=True) for p, ds in self.inputs.items()}
        out = self.stage.run(self.context(), **self.given)
        if not isinstance(out, xr.Dataset):
            raise Broken(f"run() returned a {type(out).__name__}")
        same = [p for p, ds in self.given.items() if out is ds]
        if same:
            raise Broken(f"run() returned its input {same[0]!r} itself")
        self.result = out

    def output_schema(self) -> None:
        if self.stage.output is None:
            raise NotApplicable("the stage declares no output schema (any Dataset)")
        try:
            self.stage.output.validate(self.result, stage=self.stage.name, port="output")
        except SpflowError as exc:
            raise Broken(str(exc)) from None

    def output_units(self) -> None:
        bare = [str(n) for n, v in self.result.data_vars.items()
                if v.dtype.kind in "iufc" and not isinstance(v.attrs.get("units"), str)
                and not has_units_per_element(self.result, n)]
        if bare:
            raise Broken(f"numeric variables without a 'units' attribute: {bare}")

    def purity(self) -> None:
        changed = [f"port {p!r}: " + "; ".join(d) for p in self.inputs
                   if (d := differences(self.inputs[p], self.given[p]))]
        self.impure = bool(changed)
        if changed:
            raise Broken("run() changed its inputs: " + " | ".join(changed))

    def determinism(self) -> None:
        again = self.rerun()
        found = differences(self.result, again) if isinstance(again, xr.Dataset) else [f"a {type(again).__name__}"]
        if found:
            raise Broken("a second run differs: " + "; ".join(found))

    def cache_round_trip(self) -> None:
        try:
            back = cache_round_trip(self.result, where=f"stage {self.stage.name!r} output")
        except SpflowError as exc:
            raise Broken(f"the cache refuses the result: {exc}") from None
        found = differences(self.result, back)
        if found:
            raise Broken("read back from the cache it differs: " + "; ".join(found))
        if self.stage.output is not None and _valid(self.stage.output, self.result):
            try:
                self.stage.output.validate(back, stage=self.stage.name, port="output (read back from the cache)")
            except SpflowError as exc:
                raise Broken(str(exc)) from None

    def nan_inputs(self, as_missing: set[str]) -> None:
        schemas = type(self.stage).inputs
        tried, problems = [], []
        for port in sorted(self.inputs):
            schema = schemas.get(port)
            declared = schema.variables if schema is not None else {}
            names = [n for n in float_data_variables(self.inputs[port]) if n not in declared or declared[n].allow_nan]
            if not names:
                continue
            tried.append(port)
            poisoned = dict(self.inputs, **{port: with_nan(self.inputs[port], names)})
            given = {p: ds.copy(deep=True) for p, ds in poisoned.items()}
            what = f"a NaN in port {port!r} (variables {names})"
            try:
                out = self.stage.run(self.context(), **given)
            except SpflowError:
                continue  # rejected with a clear error
            except Exception as exc:  # noqa: BLE001 - the finding is that it was not a spflow error
                problems.append(f"{what} raised {type(exc).__name__}: {exc} (not a spflow error naming the input)")
                continue
            if not isinstance(out, xr.Dataset):
                problems.append(f"{what}: run() returned a {type(out).__name__}")
                continue
            if not self.impure and differences(given[port], poisoned[port]):  # (else purity has said so)
                problems.append(f"with {what} run() changed that input")
            if self.stage.output is not None:
                try:
                    self.stage.output.validate(out, stage=self.stage.name, port="output")
                except SpflowError as exc:
                    problems.append(f"{what} gave a result that breaks the output schema: {exc}")
                    continue
            if port in as_missing or not differences(out, self.result):
                continue  # documented as missing data, or not read
            if _nan_count(out) <= _nan_count(self.result):
                problems.append(f"{what} changed the result without any new NaN in it (silently turned into numbers)")
        if not tried:
            raise NotApplicable("no input has a float variable its schema lets NaN through")
        if problems:
            raise Broken("; ".join(problems))


def _valid(schema: DatasetSchema, ds: xr.Dataset) -> bool:
    try:
        schema.validate(ds, stage="", port="")
    except SpflowError:
        return False
    return True


def _nan_count(ds: xr.Dataset) -> int:
    return sum(int(np.isnan(v.values).sum()) for v in ds.data_vars.values() if v.dtype.kind in "fc")


def check_stage(stage: type[Stage] | Stage, inputs: Mapping[str, xr.Dataset] | None = None, *,
                params: Mapping[str, Any] | None = None, nan_as_missing: Iterable[str] = ()) -> ConformanceReport:
    """Run the stage conformance checks (module docstring) on ``stage``, a Stage class (built with ``params``) or
    instance, fed ``inputs`` (port -> Dataset; small ones keep the checks fast: the stage runs 2 + one per port with a
    float variable NaN may reach).

    Returns a :class:`~.checklist.ConformanceReport` of the passed checks; raises one
    :class:`~.checklist.ConformanceError` listing every failed check with its contract and the fix.
    """
    cls = stage if isinstance(stage, type) else type(stage)
    checks = Checklist(f"check_stage({getattr(cls, '__qualname__', cls)!r}, stage {getattr(cls, 'name', '?')!r})")
    c = STAGE_CHECKS
    if not checks.run(c["declaration"], _check_declaration, cls):
        return checks.finish()
    built: list[Stage] = []

    def construct() -> None:
        if not isinstance(stage, type):
            if params is not None:
                raise Broken("pass params only with a Stage class, not with an instance")
            built.append(stage)
            return
        try:
            built.append(stage(**dict(params or {})))
        except SpflowError as exc:
            raise Broken(f"the stage refused the params {dict(params or {})}: {exc}") from None

    if not checks.run(c["construct"], construct):
        return checks.finish()
    checks.run(c["params"], _check_params, built[0], dict(params or {}) if isinstance(stage, type) else None)
    run = _StageRun(built[0], inputs or {})
    checks.run(c["inputs"], _check_inputs, built[0], run.inputs)
    checks.run(c["runs"], run.first, needs=("inputs",))
    checks.run(c["output_schema"], run.output_schema, needs=("runs",))
    checks.run(c["output_units"], run.output_units, needs=("runs",))
    checks.run(c["purity"], run.purity, needs=("runs",))
    checks.run(c["determinism"], run.determinism, needs=("runs",))
    checks.run(c["cache_round_trip"], run.cache_round_trip, needs=("runs",))
    checks.run(c["nan_inputs"], run.nan_inputs, set(nan_as_missing),
               needs=("runs", "output_schema", "determinism"))
    return checks.finish()
