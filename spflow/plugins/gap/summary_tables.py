"""What ``spflow diagnose`` prints and puts in ``report.html`` -- and the gap section of ``spflow run gap_diagnosis``'s
and ``spflow run workflow``'s reports: the verdict, the final model's effects, the candidates' scores, the gap closed
and the numerical-error scale as :class:`~spflow.core.report_table.Table` objects with their units (the terminal gets
them as aligned text, the report as HTML tables), read off the :func:`~spflow.plugins.gap.report.summary` of a report.

Log-density scores (ΔELPD and its standard error) are in nats, UDUNITS ``"1"``; fitted strengths are an effect's
dimensionless scale (``spflow list effects``; the gap report writes them with units ``"1"``), so ``"1"`` as well.
"""

from __future__ import annotations

from spflow.core.report_table import Table

__all__ = ["summary_items"]


def _or_dash(value):
    """A missing number (``None`` in the summary) as NaN, which a table shows as ``-``."""
    return float("nan") if value is None else value


def _verdict(result: dict) -> list[str | Table]:
    items: list[str | Table] = [Table(
        ["verdict", "ambiguity set", "declared effects", "final model"],
        [[result["verdict"], ", ".join(result["ambiguity_set"]) or "-",
          ", ".join(e["name"] for e in result["effects"]) or "-", result["final_model"] or "-"]],
        title="Verdict")]
    if result["effects"]:
        items.append(Table(["effect", "fitted strength"],
                           [[e["name"], _or_dash(e["strength"])] for e in result["effects"]], units=["", "1"],
                           title="Final model's effects (strength: the effect's scale, spflow list effects)"))
    fit = result["fit"]
    items.append(Table(["omnibus p", "targeted p", "base chi2", "dof"],
                       [[_or_dash(fit["chi2_pvalue"]), _or_dash(fit.get("targeted_pvalue")), _or_dash(fit["chi2_base"]),
                         _or_dash(fit["dof"])]], units=["1", "1", "1", "1"],
                       title="Calibration gap: significant when either test's p is below the diagnosis's alpha "
                             "(targeted: the largest candidate misfit drop, Bonferroni over the catalogue)"))
    if result["verdict"] in ("unattributed", "out_of_catalogue"):
        where = ", ".join(f"{c['variable']}:{c['experiment']}:{c['slug']}" for c in result["gap_cells"][:5])
        items.append(f"the gap is real (chi2 {result['fit']['chi2_base']} on {result['fit']['dof']:g} dof) but not "
                     f"attributable to a catalogued mechanism; where: {where or 'no single cell'}")
    return items + [f"note: {note}" for note in result.get("notes", [])]


def _candidates(result: dict) -> Table:
    declared = {e["name"] for e in result["effects"]}
    tried = {t["name"] for t in result["tried_not_declared"]}
    rows = []
    for r in result["ranked_effects"]:
        state = "declared" if r["name"] in declared else "tried, not declared" if r["name"] in tried else \
            "shortlisted" if r["shortlisted"] else "screened out"
        rows.append([r["name"], state, _or_dash(r["screen_z"]), _or_dash(r.get("fitted_strength")),
                     _or_dash(r.get("delta_elpd")), _or_dash(r.get("delta_elpd_se")), _or_dash(r.get("gap_closed")),
                     "" if "passes" not in r else "yes" if r["passes"] else "no"])
    return Table(["candidate", "state", "screening z", "fitted strength", "delta ELPD", "delta ELPD SE",
                  "gap closed", "passes the rule"], rows, units=["", "", "1", "1", "1", "1", "1", ""],
                 title="Candidate scores (first step; delta ELPD in nats, strength: the effect's scale)")


def _gap_closed(result: dict, seconds: float | None) -> Table:
    fit, closed = result["fit"], result["gap_closed"]
    rows = [["calibration", _or_dash(closed["calibration"]), _or_dash(fit["chi2_base"]), _or_dash(fit["chi2_final"])],
            ["held-out", _or_dash(closed["heldout"]), _or_dash(fit["chi2_heldout_base"]),
             _or_dash(fit["chi2_heldout_final"])]]
    return Table(["data", "gap closed", "chi2 base", "chi2 final"], rows, units=["", "1", "1", "1"],
                 title=f"Gap closed ({result['forward_runs']} forward runs, "
                       + ("time not recorded)" if seconds is None else f"{seconds:.0f} s)"))


def _numerical_scale(result: dict) -> Table | None:
    error = result["numerical_error"] or {}
    scale = error.get("scale")
    if scale is None:
        return None
    return Table(["estimate", "interval lower", "interval upper", "interval level", "cap", "variants"],
                 [[scale["estimate"], scale["lower"], scale["upper"], scale["level"], scale["maximum"],
                   "; ".join(error["variants"])]], units=["1", "1", "1", "1", "1", ""],
                 title="Numerical error in the error model: scale x the spread of the variants (estimated from the "
                       "base model's calibration residuals)")


def _path_reruns(result: dict) -> list[str | Table]:
    """The reruns along other optimiser paths (none: a line saying the verdict's stability was not checked)."""
    reruns = result.get("path_reruns", [])
    if not reruns:
        return ["verdict along other optimiser paths: not checked (path_reruns = 0)"]
    rows = [[r["diff_step"], r["verdict"], ", ".join(r["ambiguity_set"]) or "-",
             ", ".join(f"{k} {v:.3g}" for k, v in r["effects"].items()) or "-", r["forward_runs"],
             "yes" if r["agrees"] else "no"] for r in reruns]
    table = Table(["difference step", "verdict", "ambiguity set", "declared effects (strength)", "forward runs",
                   "agrees"], rows, units=["1", "", "", "", "1", ""],
                  title="Verdict along other optimiser paths (the whole diagnosis rerun with another relative "
                        "difference step)")
    agree = sum(r["agrees"] for r in reruns)
    if agree == len(reruns):
        line = f"the verdict holds along {agree} of {len(reruns)} other optimiser paths"
    else:
        seen = sorted({result["verdict"]} | {r["verdict"] for r in reruns})
        line = (f"the verdict changes along {len(reruns) - agree} of {len(reruns)} other optimiser paths: it is a "
                f"finding of the optimiser's path, not of the data; read it as uncertain between {', '.join(seen)} "
                "and the sets listed")
    return [table, line]


def summary_items(result: dict, seconds: float | None) -> list[str | Table]:
    """The verdict, the final model's effects, candidate scores, gap closed, numerical-error scale and the reruns
    along other optimiser paths of a diagnosis summary ``result`` (``summary.json``), the diagnosis having taken
    ``seconds`` (``None``: not recorded): tables, and the lines saying where an unattributed gap is, the
    diagnosis's notes and whether the verdict holds along other paths."""
    scale = _numerical_scale(result)
    return [*_verdict(result), _candidates(result), _gap_closed(result, seconds), *([scale] if scale else []),
            *_path_reruns(result)]
