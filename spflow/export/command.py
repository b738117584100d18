"""``spflow export opm`` and ``spflow compare opm``: the OPM Flow bridge from the command line.

    spflow export opm --schedule SCHEDULE [--params FILE] [--effect NAME=VALUE ...] --out DIR [--cells N]
                      [--pv-step PV] [--area-scale X] [--rock-density KG_M3] [--approximate]
    spflow compare opm (the same options) [--scheme upwind|tvd]

``SCHEDULE`` is a Table 2.5 name (``BCF1``..) or a TOML/JSON file ``{name = ..., slugs = [{pv, salinity_ppm,
polymer_ppm, ...}, ...]}``. ``--params`` is a TOML/JSON file with the forward-model parameters: a flat table
``{NAME = value}`` (the defaults, a calibration's best point, a posterior sample) or with ``[parameters]`` and
``[effects]`` tables; ``--effect`` overrides effect strengths. ``export`` writes ``DIR/CORE.DATA``; ``compare``
also runs OPM Flow and spflow and writes ``opm.nc``, ``spflow.nc``, ``comparison.csv`` and ``comparison.png``.
"""

from __future__ import annotations

import argparse
import json
import tomllib
from pathlib import Path

from spflow.core.errors import ParameterError

__all__ = ["add_parser", "main"]


def _common(p) -> None:
    p.add_argument("target", choices=["opm"], help="the simulator (OPM Flow)")
    p.add_argument("--schedule", required=True, help="Table 2.5 name or a TOML/JSON schedule file")
    p.add_argument("--params", metavar="FILE", help="TOML/JSON forward-model parameters (default: the defaults)")
    p.add_argument("--effect", action="append", default=[], metavar="NAME=VALUE", help="effect strength override")
    p.add_argument("--out", required=True, metavar="DIR")
    p.add_argument("--cells", type=int, default=100)
    p.add_argument("--pv-step", type=float, default=0.01, help="report/summary interval, PV (default 0.01)")
    p.add_argument("--area-scale", type=float, help="cross-section and rate scale (default: a 1e4 m2 section)")
    p.add_argument("--rock-density", type=float, default=2650.0, help="kg/m3, converts adsorption to kg/kg rock")
    p.add_argument("--approximate", action="store_true",
                   help="export mechanisms OPM cannot express with printed approximations instead of refusing")


def add_parser(sub) -> None:
    """Add the ``export`` and ``compare`` subcommands to an argparse subparsers object."""
    _common(sub.add_parser("export", help="write an OPM Flow deck of a coreflood model"))
    p = sub.add_parser("compare", help="run OPM Flow and spflow on a coreflood and compare them")
    _common(p)
    p.add_argument("--scheme", choices=["upwind", "tvd"], default="upwind", help="spflow's scheme (default upwind)")


def _load(path: str, what: str) -> dict:
    file = Path(path)
    if not file.is_file():
        raise ParameterError(f"{what} {path!r}: no such file")
    try:
        if file.suffix.lower() == ".json":
            return json.loads(file.read_text())
        with file.open("rb") as fh:
            return tomllib.load(fh)
    except (tomllib.TOMLDecodeError, json.JSONDecodeError) as exc:
        raise ParameterError(f"{what} {path!r}: not valid {file.suffix.lstrip('.').upper() or 'TOML'}: {exc}") from None


def _inputs(args: argparse.Namespace):
    schedule = args.schedule
    if Path(schedule).suffix.lower() in (".toml", ".json"):
        schedule = _load(schedule, "--schedule")
    params, effects = {}, {}
    if args.params:
        data = _load(args.params, "--params")
        if "parameters" in data or "effects" in data:
            unknown = sorted(set(data) - {"parameters", "effects"})
            if unknown:
                raise ParameterError(f"--params {args.params!r}: unknown table(s) {unknown}; allowed "
                                     "['parameters', 'effects'] or a flat NAME = value table")
            params, effects = dict(data.get("parameters", {})), dict(data.get("effects", {}))
        else:
            params = dict(data)
    for item in args.effect:
        name, sep, value = item.partition("=")
        try:
            effects[name.strip()] = float(value)
        except ValueError:
            sep = ""
        if not sep:
            raise ParameterError(f"--effect {item!r}: expected NAME=VALUE with a number, e.g. shear_thinning=0")
    return schedule, params, effects


def main(args: argparse.Namespace) -> int:
    """Run ``spflow export opm`` or ``spflow compare opm`` (``args.command``)."""
    schedule, params, effects = _inputs(args)
    out = Path(args.out)
    options = {"area_scale": args.area_scale, "rock_density": args.rock_density}
    if args.command == "export":
        from .opm_deck import write_opm_deck

        deck = write_opm_deck(out / "CORE.DATA", schedule, params, effects, args.cells, approximate=args.approximate,
                              pv_step=args.pv_step, **options)
        print(f"wrote {deck.path}")
        return 0
    from .opm_compare import compare_opm

    _, _, rows = compare_opm(schedule, params, effects, cells=args.cells, scheme=args.scheme, pv_step=args.pv_step,
                             out=out, approximate=args.approximate, **options)
    width = max(len(r["quantity"]) for r in rows)
    print(f"{'quantity':<{width}}  {'OPM Flow':>12}  {'spflow':>12}  difference")
    for r in rows:
        diff = f"{100 * r['difference']:+.2f} %" if r["difference_unit"] == "relative" else f"{r['difference']:+.4g}"
        print(f"{r['quantity']:<{width}}  {r['opm']:>12.6g}  {r['spflow']:>12.6g}  {diff}")
    print(f"wrote {out / 'comparison.csv'}, {out / 'comparison.png'}, {out / 'opm.nc'}, {out / 'spflow.nc'}")
    return 0
