"""``spflow export opm`` and ``spflow compare opm``: the OPM Flow bridge from the command line.

    spflow export opm [--study FILE --experiment NAME] [--schedule SCHEDULE] [--params FILE]
                      [--calibration FILE.nc | --posterior FILE.nc --draw K|mean] [--effect NAME=VALUE ...]
                      --out DIR [--cells N] [--pv-step PV] [--max-step-pv PV|none] [--area-scale X]
                      [--rock-density KG_M3] [--shear-sw SW] [--approximate]
    spflow compare opm (the same options) [--scheme upwind|tvd]

``--study``/``--experiment`` take the experiment's core, rate (and per-slug rates), schedule, fluids, the study's
fixed parameters and its base-model effects. ``SCHEDULE`` is a Table 2.5 name (``BCF1``..) or a TOML/JSON file
``{name = ..., slugs = [{pv, salinity_ppm, polymer_ppm, ...}, ...]}``; it overrides the experiment's. ``--params``
is a TOML/JSON file with forward-model parameters: a flat table ``{NAME = value}`` or with ``[parameters]`` and
``[effects]`` tables. ``--calibration`` takes the noise-consistent best point (``confidence_best``) of an
``nsga2_calibration`` result, ``--posterior`` a draw (chain-major index) or the mean of an MCMC posterior; a
parameter given by ``--params`` and one of them is refused. ``--effect`` overrides effect strengths. Every value
taken is printed with its source (:mod:`.opm_model`). ``--max-step-pv`` caps OPM's time steps (default
``DEFAULT_MAX_STEP_PV`` of :mod:`.opm_time_steps`; ``none``: OPM's own step control). ``export`` writes
``DIR/CORE.DATA``; ``compare`` also runs OPM Flow and spflow and writes ``opm.nc``, ``spflow.nc``,
``comparison.csv`` and ``comparison.png``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from spflow.core.errors import ParameterError

from .opm_time_steps import DEFAULT_MAX_STEP_PV

__all__ = ["add_parser", "main"]


def _max_step(text: str) -> float | None:
    """``--max-step-pv``'s value: a number or ``none``."""
    return None if text.strip().lower() == "none" else float(text)


def _common(p) -> None:
    p.add_argument("target", choices=["opm"], help="the simulator (OPM Flow)")
    p.add_argument("--study", metavar="FILE", help="a study file (with --experiment)")
    p.add_argument("--experiment", metavar="NAME", help="the study's experiment whose core, rate, schedule and "
                   "fluids are exported")
    p.add_argument("--schedule", help="Table 2.5 name or a TOML/JSON schedule file (overrides the experiment's)")
    p.add_argument("--params", metavar="FILE", help="TOML/JSON forward-model parameters")
    p.add_argument("--calibration", metavar="FILE.nc",
                   help="an nsga2_calibration result: take its noise-consistent best point (confidence_best)")
    p.add_argument("--posterior", metavar="FILE.nc", help="an MCMC posterior (emcee_sampler / mh_sampler result)")
    p.add_argument("--draw", metavar="K|mean", help="the posterior draw (chain-major index) or 'mean'")
    p.add_argument("--effect", action="append", default=[], metavar="NAME=VALUE", help="effect strength override")
    p.add_argument("--out", required=True, metavar="DIR")
    p.add_argument("--cells", type=int, default=100)
    p.add_argument("--pv-step", type=float, default=0.01, help="report/summary interval, PV (default 0.01)")
    p.add_argument("--max-step-pv", type=_max_step, default=DEFAULT_MAX_STEP_PV, metavar="PV|none",
                   help=f"cap on OPM's time steps, PV of the slug injected (default {DEFAULT_MAX_STEP_PV:g}; 'none': "
                   "OPM's own steps, whose time error can exceed a lab's noise)")
    p.add_argument("--area-scale", type=float, help="cross-section and rate scale (default: a 1e4 m2 section)")
    p.add_argument("--rock-density", type=float, default=2650.0, help="kg/m3, converts adsorption to kg/kg rock")
    p.add_argument("--shear-sw", type=float, metavar="SW",
                   help="water saturation at which shear thinning is matched in a two-phase core (default 1 - S2RWC)")
    p.add_argument("--approximate", action="store_true",
                   help="export mechanisms OPM cannot express with printed approximations instead of refusing")


def add_parser(sub) -> None:
    """Add the ``export`` and ``compare`` subcommands to an argparse subparsers object."""
    _common(sub.add_parser("export", help="write an OPM Flow deck of a coreflood model"))
    p = sub.add_parser("compare", help="run OPM Flow and spflow on a coreflood and compare them")
    _common(p)
    p.add_argument("--scheme", choices=["upwind", "tvd"], default="upwind", help="spflow's scheme (default upwind)")


def _effects(items: list[str]) -> dict[str, float]:
    effects = {}
    for item in items:
        name, sep, value = item.partition("=")
        try:
            effects[name.strip()] = float(value)
        except ValueError:
            sep = ""
        if not sep:
            raise ParameterError(f"--effect {item!r}: expected NAME=VALUE with a number, e.g. shear_thinning=0")
    return effects


def _sources(args: argparse.Namespace) -> dict:
    return {"study": args.study, "experiment": args.experiment, "schedule": args.schedule, "params": args.params,
            "effects": _effects(args.effect), "calibration": args.calibration, "posterior": args.posterior,
            "draw": args.draw}


def main(args: argparse.Namespace) -> int:
    """Run ``spflow export opm`` or ``spflow compare opm`` (``args.command``)."""
    out = Path(args.out)
    options = {"area_scale": args.area_scale, "rock_density": args.rock_density, "shear_sw": args.shear_sw,
               "max_step_pv": args.max_step_pv}
    if args.command == "export":
        from .opm_model import export_opm

        deck = export_opm(out, cells=args.cells, approximate=args.approximate, pv_step=args.pv_step,
                          **_sources(args), **options)
        print(f"wrote {deck.path}")
        return 0
    from .opm_compare import compare_opm
    from .opm_model import resolve_model

    model = resolve_model(**_sources(args))
    lines = model.lines()
    print("\n".join(lines))
    _, _, rows = compare_opm(model.schedule, model.params, model.effects, cells=args.cells, scheme=args.scheme,
                             pv_step=args.pv_step, out=out, approximate=args.approximate, provenance=lines,
                             **options)
    width = max(len(r["quantity"]) for r in rows)
    print(f"{'quantity':<{width}}  {'OPM Flow':>12}  {'spflow':>12}  difference")
    for r in rows:
        diff = f"{100 * r['difference']:+.2f} %" if r["difference_unit"] == "relative" else f"{r['difference']:+.4g}"
        print(f"{r['quantity']:<{width}}  {r['opm']:>12.6g}  {r['spflow']:>12.6g}  {diff}")
    print(f"wrote {out / 'comparison.csv'}, {out / 'comparison.png'}, {out / 'opm.nc'}, {out / 'spflow.nc'}")
    return 0
