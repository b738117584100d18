"""How far a catalogue effect can mimic the departure of finished twins (docs/gap_validation.md, out-of-catalogue
twins): for each twin of a results file of ``scripts/gap_validation.py`` the cosine, in the whitened calibration
data (BCF1, the twin's likelihood variables), between the twin's true departure from the base model and the
change the named effect makes at its strength step 0 fitted (the record's), both at the truth's parameters, before
and after the base parameters' directions are projected out (``NuisanceProjector`` at ``Options.nuisance_scale``,
as the fingerprint SNR; and exactly). A projected cosine near +1 means that recalibrating the base model plus that
effect reproduces what the base alone cannot: the diagnosis then has only the held-out coreflood to tell the two
apart. Negative means the effect cannot reach the departure at any strength of the sign it has.

    python scripts/mimicry.py --results out/gap_validation_v12 --effect capillary_pressure
"""

from __future__ import annotations

import argparse
import importlib.util
import json
from pathlib import Path

import numpy as np

from spflow.plugins.gap.base_model import BaseModel
from spflow.plugins.gap.diagnosis import Options
from spflow.plugins.gap.fingerprints import NuisanceProjector
from spflow.plugins.gap.layout import make_layout
from spflow.plugins.gap.least_squares import WhitenedProblem
from spflow.plugins.gap.observed import load_experiments
from spflow.plugins.gap.prediction import Predictor

_spec = importlib.util.spec_from_file_location("gap_validation", Path(__file__).with_name("gap_validation.py"))
gap_validation = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(gap_validation)


def cosines(record: dict, effect: str) -> dict:
    """The raw and projected whitened cosines between ``record``'s true departure and ``effect`` at its step-0
    strength (NaN where step 0 did not fit it or a forward run failed)."""
    tried = {s["name"]: s for s in record["step0"]}.get(effect)
    strength = float("nan") if tried is None else float(tried["strength"])
    out = {"id": record["id"], "truth": {**record["truth_effects"], **record["truth_fixed"]}, "strength": strength,
           "verdict": record["verdict"], "accepted": record["accepted"]}
    if not np.isfinite(strength):
        return out | {"raw": float("nan"), "projected": float("nan"), "exact": float("nan")}
    base, truth, data = gap_validation.twin(gap_validation.twin_spec(record), record["cells"], record["seed"])
    cal = load_experiments([data[0]], 0.1)
    layout = make_layout(cal, tuple(record["variables"]))
    predictor = Predictor(base, cal)
    truth_model = BaseModel(base.parameters, {**base.fixed, **truth["fixed"]}, base.effects, base.cells)
    runs = [predictor.predict([(truth["u"], None)], layout.experiments, layout.variables)[0],
            Predictor(truth_model, cal).predict([(truth["u"], truth["effects"] or None)], layout.experiments,
                                                layout.variables)[0],
            predictor.predict([(truth["u"], {effect: strength})], layout.experiments, layout.variables)[0]]
    if any(y is None for y in runs):
        return out | {"raw": float("nan"), "projected": float("nan"), "exact": float("nan")}
    base_y, truth_y, effect_y = (layout.vector(y) for y in runs)
    g, h = layout.whiten(truth_y - base_y), layout.whiten(effect_y - base_y)
    jac = WhitenedProblem(predictor, layout, (), len(base.parameters), 0.01).jac(truth["u"])

    def cosine(p: NuisanceProjector | None) -> float:
        if p is None:
            return float(g @ h / np.linalg.norm(g) / np.linalg.norm(h))
        return p.inner(g, h) / max(p.norm(g) * p.norm(h), 1e-300)

    return out | {"raw": cosine(None), "projected": cosine(NuisanceProjector(jac, Options.nuisance_scale)),
                  "exact": cosine(NuisanceProjector(jac, float("inf")))}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--results", required=True, help="a results directory of scripts/gap_validation.py")
    p.add_argument("--effect", default="capillary_pressure", help="the catalogue effect (default capillary_pressure)")
    p.add_argument("--scenario", default="out_of_catalogue", help="twins whose scenario starts with this")
    p.add_argument("--cells", type=int, default=30)
    args = p.parse_args(argv)
    lines = (Path(args.results) / "dp_oil.jsonl").read_text().splitlines()
    records = [r for r in map(json.loads, lines)
               if r["cells"] == args.cells and r["scenario"].startswith(args.scenario)]
    print(f"| twin | truth | {args.effect} strength (step 0) | cosine raw | projected | exact | verdict | accepted |")
    print("|---|---|---|---|---|---|---|---|")
    for r in records:
        c = cosines(r, args.effect)
        truth = ", ".join(f"{k} {v:.3g}" for k, v in c["truth"].items()) or "–"
        print(f"| {c['id']} | {truth} | {c['strength']:.3g} | {c['raw']:.3f} | {c['projected']:.3f} | "
              f"{c['exact']:.3f} | {c['verdict']} | {json.dumps(c['accepted'])} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
