"""Tiny stages for framework tests. Every run appends its node to a log file so that tests can count executions
across processes."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import xarray as xr

import spflow
from spflow import DatasetSchema, Param, Stage, Variable

SERIES = DatasetSchema(dims=("x",), variables={"y": Variable(("x",), units="m")})


def _log(path: str, name: str) -> None:
    if path:
        with open(path, "a") as fh:
            fh.write(name + "\n")


def executions(log: Path) -> list[str]:
    return log.read_text().split() if log.exists() else []


def _wait_for(path: str, seconds: float = 60.0) -> None:
    """Block until the file ``path`` exists (another node creates it); fail after ``seconds``."""
    deadline = time.monotonic() + seconds
    while path and not Path(path).exists():
        if time.monotonic() > deadline:
            raise RuntimeError(f"gave up waiting for {path}: the node creating it never ran")
        time.sleep(0.01)


class Source(Stage):
    name = "toy_source"
    description = "y = value * arange(n)"
    output = SERIES
    params = {
        "value": Param(float, 1.0, bounds=(-100.0, 100.0), unit="m"),
        "n": Param(int, 5, bounds=(1, 10_000)),
        "log": Param(str, ""),
        "delay": Param(float, 0.0, bounds=(0.0, 10.0), unit="s", doc="sleep this long (to overlap concurrent runs)"),
        "wait_for": Param(str, "", doc="finish only once this file exists (another node creates it)"),
    }

    def run(self, ctx, **inputs):
        time.sleep(self.params["delay"])
        _wait_for(self.params["wait_for"])
        _log(self.params["log"], f"source:{self.params['value']}")
        y = self.params["value"] * np.arange(self.params["n"], dtype=float)
        return xr.Dataset({"y": ("x", y, {"units": "m"})})


class Scale(Stage):
    name = "toy_scale"
    description = "y * factor"
    inputs = {"data": SERIES}
    output = SERIES
    params = {"factor": Param(float, 2.0, bounds=(0.0, 10.0)), "log": Param(str, ""),
              "delay": Param(float, 0.0, bounds=(0.0, 10.0), unit="s"),
              "touch": Param(str, "", doc="create this file when running (a signal to a waiting node)")}

    def run(self, ctx, data):
        time.sleep(self.params["delay"])
        if self.params["touch"]:
            Path(self.params["touch"]).touch()
        _log(self.params["log"], f"scale:{self.params['factor']}")
        return data * self.params["factor"]


class Add(Stage):
    name = "toy_add"
    inputs = {"a": SERIES, "b": SERIES}
    output = SERIES
    params = {"log": Param(str, "")}

    def run(self, ctx, a, b):
        _log(self.params["log"], "add")
        out = a + b
        out["y"].attrs["units"] = "m"
        return out


class Fail(Stage):
    name = "toy_fail"
    inputs = {"data": SERIES}
    output = SERIES
    params = {"kind": Param(str, "error", choices=["error", "interrupt", "none"]), "log": Param(str, "")}

    def run(self, ctx, data):
        _log(self.params["log"], "fail")
        if self.params["kind"] == "error":
            raise RuntimeError("boom from toy_fail")
        if self.params["kind"] == "interrupt":
            raise KeyboardInterrupt
        return data


class BadOutput(Stage):
    name = "toy_bad_output"
    output = SERIES
    params = {"mode": Param(str, "units", choices=["units", "missing", "dims", "nan", "type"])}

    def run(self, ctx):
        mode = self.params["mode"]
        if mode == "units":
            return xr.Dataset({"y": ("x", np.zeros(3), {"units": "ft"})})
        if mode == "missing":
            return xr.Dataset({"z": ("x", np.zeros(3), {"units": "m"})})
        if mode == "dims":
            return xr.Dataset({"y": ("t", np.zeros(3), {"units": "m"})})
        if mode == "nan":
            return xr.Dataset({"y": ("x", np.array([0.0, np.nan]), {"units": "m"})})
        return {"y": 1}


class InnerParallel(Stage):
    """Reports the worker budget it was given (one parallel layer per level)."""

    name = "toy_inner"
    inputs = {"data": SERIES}
    output = SERIES
    params = {"tag": Param(int, 0, bounds=(0, 100))}

    def run(self, ctx, data):
        values = ctx.parallel()(_square_delayed(v) for v in data["y"].values)
        out = xr.Dataset({"y": ("x", np.asarray(values, dtype=float), {"units": "m"})})
        out.attrs["n_jobs"] = ctx.n_jobs
        return out


class Steps(Stage):
    """Counts ``n`` steps through ``ctx.progress`` (each ``pause`` seconds long) and returns y = arange(n)."""

    name = "toy_steps"
    output = SERIES
    params = {"n": Param(int, 5, bounds=(1, 10_000)), "pause": Param(float, 0.0, bounds=(0.0, 1.0), unit="s")}

    def run(self, ctx):
        for _ in ctx.progress(range(self.params["n"]), what="steps"):
            time.sleep(self.params["pause"])
        return xr.Dataset({"y": ("x", np.arange(self.params["n"], dtype=float), {"units": "m"})})


def _square(v: float) -> float:
    return v * v


def _square_delayed(v):
    from joblib import delayed

    return delayed(_square)(v)


STAGES = [Source, Scale, Add, Fail, BadOutput, InnerParallel, Steps]


@spflow.hookimpl
def spflow_register_stages(register):
    for cls in STAGES:
        register(cls)
