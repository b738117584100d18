"""Reproduce thesis Fig. 3.15: the PC-Kriging proxy's mean ± 2σ band over PV against simulator runs (BCF1).

As in §3.8: the 9 parameters of Table 3.2, N_s = 200 LHS training runs of BCF1, the same space and design as the PCE.
A pipeline (``parameter_space`` -> ``lhs_design`` -> ``forward`` -> ``pck`` / ``pce``, cached in ``--cache``) fits
both proxies of the Δp and recovery series; ``--validation`` independent LHS runs score them. The figure
(:func:`spflow.plugins.surrogates.figures.band_figure`) shows, for three of the validation parameter sets, the
simulator (markers), the PC-Kriging mean with its ±2σ band and the PCE mean (top), and -- since the band is thin at
that scale -- the band around the proxy mean with the simulator's offsets from both proxies (bottom). Writes
``docs/figures/fig_3_15_pck_band.png`` and prints the validation errors and 2σ coverage.

Run: ``.venv/bin/python benchmarks/figures/fig_3_15_pck_band.py [--samples 200] [--validation 200] [--jobs 2]``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]

import spflow  # noqa: E402
from spflow.plugins.design.thesis_tables import TABLE_3_2  # noqa: E402
from spflow.plugins.surrogates.contract import load_surrogate  # noqa: E402
from spflow.plugins.surrogates.figure_data import two_sigma_coverage  # noqa: E402
from spflow.plugins.surrogates.figures import band_figure  # noqa: E402
from spflow.plugins.surrogates.regression import is_constant  # noqa: E402
from spflow.plugins.surrogates.training_data import training_set  # noqa: E402

QOIS = (("dp", 1e-3, "Δp (kPa)"), ("recovery", 1.0, "recovery (fraction OOIP)"))


def pipeline(samples: int, validation: int, cells: int, proxies: dict[str, tuple[str, dict]]) -> spflow.Pipeline:
    """Table 3.2 space, training and validation LHS runs of BCF1, and one node per proxy (name -> stage, params)."""
    p = spflow.Pipeline("fig_3_15")
    p.add("space", "parameter_space", params={"names": list(TABLE_3_2), "ranges": TABLE_3_2})
    forward = {"experiments": ["BCF1"], "cells": cells, "pv_step": 0.1}
    for name, size, seed in (("train", samples, 1), ("val", validation, 2)):
        p.add(f"design_{name}", "lhs_design", inputs={"space": "space"}, params={"samples": size, "seed": seed})
        p.add(f"runs_{name}", "forward", inputs={"design": f"design_{name}"}, params=forward)
    wiring = {"space": "space", "design": "design_train", "responses": "runs_train"}
    for node, (stage, params) in proxies.items():
        p.add(node, stage, inputs=wiring, params={"variables": [q for q, _, _ in QOIS], **params})
    return p


def validation_scores(model, data) -> dict[str, tuple[float, float]]:
    """Per QoI: ε_val^mean -- Σ(y − μ)²/Σ(y − ȳ)² per PV step on the validation runs (the form of Eq. 3.8), averaged
    over PV (Eq. 3.9), with steps constant up to round-off counted as 0 as in the PCE's LOO -- and the fraction of
    validation values inside μ ± 2σ."""
    mean, var = model.predict(data.x)
    out = {}
    for qoi, _, _ in QOIS:
        cols = data.outputs.columns(qoi, "BCF1")
        y, mu = data.y[:, cols], mean[:, cols]
        err, spread = np.sum((mu - y) ** 2, axis=0), np.sum((y - y.mean(axis=0)) ** 2, axis=0)
        eps = np.divide(err, spread, out=np.zeros_like(err), where=~is_constant(y))
        out[qoi] = (float(np.mean(eps)), two_sigma_coverage(y, mu, var[:, cols]))
    return out


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=200)
    parser.add_argument("--validation", type=int, default=200)
    parser.add_argument("--cells", type=int, default=100)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--cache", type=Path, default=ROOT / ".spflow")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "figures" / "fig_3_15_pck_band.png")
    parser.add_argument("--refit", action="store_true",
                        help="refit the proxies even if cached (the cache fingerprints stage classes, not helpers)")
    args = parser.parse_args(argv)

    proxies = {"pck": ("pck", {"mode": "sequential", "degree_max": 3}),
               "pce": ("pce", {"solver": "lars", "degree_max": 5})}
    result = spflow.run(pipeline(args.samples, args.validation, args.cells, proxies), cache=args.cache,
                        jobs=args.jobs, force=list(proxies) if args.refit else ())
    models = {name: load_surrogate(result[name]) for name in proxies}
    val = training_set(result["space"], result["design_val"], result["runs_val"], [q for q, _, _ in QOIS], ["BCF1"])
    print(f"{'proxy':>6} {'QoI':>9} {'eps_LOO^mean':>13} {'eps_val^mean':>13} {'2σ coverage':>12}")
    for name, model in models.items():
        for qoi, (eps, cover) in validation_scores(model, val).items():
            loo = np.mean(model.loo[val.outputs.columns(qoi, "BCF1")])
            print(f"{name:>6} {qoi:>9} {loo:13.2e} {eps:13.2e} {cover:12.3f}")

    band_figure(result["pck"], result["design_val"], result["runs_val"], args.out, n_show=3, reference=result["pce"],
                variables=[q for q, _, _ in QOIS])
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
