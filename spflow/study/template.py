"""``spflow init``: a commented study file filled from the data files' metadata, valid as written.

What the data files state is used (and said so in a comment); what they leave out and the schema does not let
default is chosen here, marked ``# DEFAULT:`` in the file and returned so the command prints it: roles (every
file calibrates except the last, held out), the calibrated parameter space (thesis Table 3.2), the base model's
effects, and core values, rate or schedule a file does not hold (the forward model's Berea values). Defaults the
schema accepts (fluids, measurement chain) are left to ``spflow check``, which lists them.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import xarray as xr

from spflow.io import load_coreflood
from spflow.io.metadata import CORE_ATTRS, core_unit
from spflow.plugins.design.thesis_tables import TABLE_3_2
from spflow.plugins.forward.effects import default_registry
from spflow.plugins.forward.parameters import PARAMETERS
from spflow.synthetic.noise_model import NoiseModel

from .bundled import bundled_study_path
from .errors import StudyError
from .schema import CORE_KEYS, FLUID_KEYS, FROM_DATA, MEASUREMENT_KEYS, MEASUREMENT_UNITS, RATE_ATTR, VERSION

__all__ = ["study_template"]

_SPECS = {p.name: p for p in PARAMETERS}
_GROUPS = {"E2C": ("n_high", ("E1C", "E2C", "E3C")), "E2WC": ("n_low", ("E1WC", "E2WC", "E3WC"))}
_UNSAFE = re.compile(r"[^A-Za-z0-9_.-]")


def _name(ds: xr.Dataset, file: Path, taken: set) -> str:
    base = _UNSAFE.sub("_", str(ds.attrs.get("experiment") or file.stem)).lstrip("_.-") or "experiment"
    name, k = base, 2
    while name in taken:
        name, k = f"{base}_{k}", k + 1
    return name


def _quote(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _header(defaults: list[str]) -> list[str]:
    lines = [f"# spflow study (schema version {VERSION}; reference: docs/your_own_data.md).",
             "# Validate with `spflow check study.toml`; run with `spflow run workflow --study study.toml`.",
             "# Values marked '# DEFAULT:' were chosen by `spflow init`: replace them with your own.",
             f"version = {VERSION}", "",
             "# Calibrated parameters: name = [low, high] in the forward model's units (`spflow list params`),",
             "# or label = { names = [...], range = [low, high] } for one value setting several parameters.",
             "[parameters.calibrated]  # DEFAULT: the thesis's Table 3.2 space"]
    for name, (lo, hi) in TABLE_3_2.items():
        if name in _GROUPS:
            label, names = _GROUPS[name]
            lines.append(f"{label} = {{ names = [{', '.join(_quote(n) for n in names)}], range = [{lo!r}, {hi!r}] }}")
        else:
            lines.append(f"{name} = [{lo!r}, {hi!r}]")
    defaults.append("[parameters.calibrated]: the thesis's Table 3.2 parameter space")
    lines += ["", "# Fixed forward-model parameters for every experiment (not core data: that is per experiment).",
              "[parameters.fixed]", "", "# Base-model effect strengths (`spflow list effects`).",
              "[effects]  # DEFAULT: every built-in effect at its default strength"]
    registry = default_registry()
    lines += [f"{name} = {registry[name].default_strength!r}" for name in registry.names()]
    defaults.append("[effects]: every built-in effect at its default strength")
    return lines


def _experiment(file: Path, ds: xr.Dataset, name: str, role: str, directory: Path, defaults: list[str]) -> list[str]:
    attrs = ds.attrs
    rel = os.path.relpath(file.resolve(), directory.resolve())
    lines = ["", "[[experiment]]", f"name = {_quote(name)}",
             f"role = {_quote(role)}  # DEFAULT: every file calibrates except the last, held out",
             f"data = {_quote(Path(rel).as_posix())}"]
    if RATE_ATTR in attrs:
        lines.append(f"# rate: from the data file ({RATE_ATTR} = {float(attrs[RATE_ATTR]):g} ml/min)")
    else:
        default = _SPECS["QINJ"].default
        lines.append(f'rate = "{default:g} ml/min"  # DEFAULT: not in the data file; the forward model\'s value')
        defaults.append(f"experiment {name!r}: rate = {default:g} ml/min (not in the data file)")
    if "schedule" in attrs:
        lines.append(f"schedule = {_quote(FROM_DATA)}  # the data file's own schedule")
    else:
        last = max(float(ds[c].values[-1]) for c in ("pv", "pv_tube_end") if c in ds.coords)
        lines.append(f"schedule = [{{ name = \"WF\", pv = {last:.6g}, salinity_ppm = 9400.0 }}]  # DEFAULT: not in "
                     "the data file; a waterflood over the data's PV: give your slugs")
        defaults.append(f"experiment {name!r}: schedule = one 9400 ppm waterflood of {last:.6g} PV (not in the data "
                        "file)")
    lines.append("[experiment.core]  # values with units: m, cm, mm, in, ft; mD, D; fraction or %")
    for key, (attr, kind) in CORE_KEYS.items():
        unit = core_unit(attr)
        if attr in attrs:
            lines.append(f"# {key}: from the data file ({attr} = {float(attrs[attr]):g} {unit})")
        else:
            spec = _SPECS[CORE_ATTRS[attr]]
            text = f"{spec.default:g}" + ("" if kind == "fraction" else f" {unit}")
            lines.append(f"{key} = {_quote(text)}  # DEFAULT: not in the data file; the forward model's Berea value")
            defaults.append(f"experiment {name!r}: core.{key} = {text} (not in the data file)")
    lines.append("# [experiment.fluids]  (optional; missing ones take the model defaults, listed by `spflow check`)")
    lines += [f"# {key} = \"{_SPECS[key].default:g} {_SPECS[key].unit}\"" for key in FLUID_KEYS]
    noise = [key for key in MEASUREMENT_KEYS if f"noise_{key}" not in attrs]
    lines.append("[experiment.measurement]  # the measurement chain; missing fields take the documented defaults")
    for key in MEASUREMENT_KEYS:
        if key in noise:
            lines.append(f"# {key} = {getattr(NoiseModel(), key)!r}  # {MEASUREMENT_UNITS[key]}; not in the data file: "
                         "this documented default is taken unless you set it")
        else:
            lines.append(f"# {key}: from the data file ({float(attrs[f'noise_{key}']):g} {MEASUREMENT_UNITS[key]})")
    return lines


def study_template(directory: Path, data_files: list[Path]) -> tuple[str, list[str]]:
    """``(study file text, defaults chosen)`` for ``data_files`` (paths relative to ``directory``); without data
    files, the bundled study with its data copied next to it (the caller copies them)."""
    if not data_files:
        text = bundled_study_path().read_text()
        return text, ["no --data: the bundled study BCF1-BCF3 (its data files are copied next to it)"]
    defaults: list[str] = []
    lines = _header(defaults)
    taken: set = set()
    loaded = []
    for file in data_files:
        try:
            ds = load_coreflood(file)
        except ValueError as exc:
            raise StudyError(f"spflow init --data: {exc}") from None
        name = _name(ds, file, taken)
        taken.add(name)
        loaded.append((file, ds, name))
    roles = ["calibration"] * len(loaded)
    if len(loaded) > 1:
        roles[-1] = "heldout"
    for (file, ds, name), role in zip(loaded, roles):
        lines += _experiment(file, ds, name, role, directory, defaults)
    defaults.insert(0, "roles: " + ", ".join(f"{name} {role}" for (_, _, name), role in zip(loaded, roles))
                    + " (every file calibrates except the last, held out)")
    return "\n".join(lines) + "\n", defaults
