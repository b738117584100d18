"""The corefloods a lab can run next: variations of a reference schedule (issue 20, "the next experiment").

:func:`design_space` turns the reference coreflood's schedule into a list of candidate :class:`Design` s, each a
forward-model schedule with a human-readable label. The variations are the ones a lab runs on a second core plug
of the same rock, and the ones that separate the catalogue's mechanisms (docs/next_experiment.md;
Schöniger et al. 2015's justifiability analysis used for design):

* ``repeat`` — the reference schedule again (the baseline: what a replicate flood adds);
* ``concentration`` — the polymer (and surfactant) concentration of every chemical slug scaled (the viscosity law
  and the adsorption isotherm are non-linear in concentration);
* ``slug_size`` — the last polymer slug enlarged (adsorption is satisfied sooner, IPV and retention fronts move);
* ``salinity`` — the polymer slugs at another salinity (the salinity dependence of the polymer viscosity);
* ``post_flush`` — a long chase water after the last slug (residual resistance of the permeability reduction,
  desorption of reversibly adsorbed polymer);
* ``rate_step`` — the last polymer slug split in parts injected at multiples of the base rate (in-situ rheology:
  shear thinning changes the polymer mobility with the rate, permeability reduction and viscosity do not);
* ``post_flush_rate_step`` — the long post-flush as a rate staircase (residual resistance at several rates
  separates permeability reduction from a residual polymer viscosity).

Injected PV stays the time axis; a slug's ``rate_ml_min`` sets its rate (:class:`spflow.plugins.forward.schedule.
Slug`). A variation that does not apply (no polymer slug, no surfactant) is left out; every schedule is validated
on construction, and a factor or rate outside its allowed range raises ``ParameterError`` before any run.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

from spflow.core.errors import ParameterError
from spflow.plugins.forward.schedule import Schedule, Slug, as_schedule

__all__ = ["Design", "design_space", "DESIGN_KINDS"]

#: the kinds of design :func:`design_space` builds, in the order it builds them
DESIGN_KINDS = ("repeat", "concentration", "slug_size", "salinity", "post_flush", "rate_step",
                "post_flush_rate_step")


@dataclass(frozen=True)
class Design:
    """One candidate coreflood: a label a lab reads, its kind (one of :data:`DESIGN_KINDS`) and its schedule."""

    label: str
    kind: str
    schedule: Schedule


def _factors(name: str, values: Sequence[float]) -> tuple[float, ...]:
    out = []
    for v in values:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0.0:
            raise ParameterError(f"design space: {name} must be finite numbers > 0, got {v!r}")
        out.append(float(v))
    return tuple(out)


def _fmt(x: float) -> str:
    return f"{x:g}"


def _split(slug: Slug, rates: Sequence[float]) -> list[Slug]:
    """``slug`` in equal parts, part ``k`` injected at ``rates[k]`` (ml/min)."""
    part = slug.pv / len(rates)
    return [replace(slug, name=f"{slug.name}@{_fmt(q)}", pv=part, rate_ml_min=q) for q in rates]


def _schedule(name: str, slugs: Sequence[Slug]) -> Schedule:
    try:
        return Schedule(tuple(slugs), name)
    except ValueError as exc:
        raise ParameterError(f"design {name!r}: {exc}") from None


def design_space(reference, base_rate_ml_min: float, *, rate_factors: Sequence[float] = (0.5, 2.0, 4.0),
                 concentration_factors: Sequence[float] = (0.5, 1.5), salinity_factors: Sequence[float] = (0.5, 2.0),
                 slug_size_factor: float = 2.0, post_flush_pv: float = 2.0,
                 kinds: Sequence[str] | None = None) -> list[Design]:
    """Candidate designs built from the ``reference`` schedule (anything ``as_schedule`` accepts) injected at
    ``base_rate_ml_min`` (the reference run's QINJ, where a slug sets no rate of its own); see the module
    docstring. ``kinds`` restricts the result to some of :data:`DESIGN_KINDS`.

    Rate steps: the last polymer slug becomes one part at the base rate followed by one at ``f x`` the base rate
    for each factor ``f`` (one design per factor), plus a staircase through every factor; the post-flush staircase
    is the reference's last slug plus ``post_flush_pv`` PV of it, in ``len(rate_factors) + 1`` equal parts.
    """
    sched = as_schedule(reference)
    q0 = float(base_rate_ml_min)
    if not math.isfinite(q0) or q0 <= 0.0:
        raise ParameterError(f"design space: base_rate_ml_min must be a finite rate > 0 ml/min, got {base_rate_ml_min!r}")
    rate_factors = _factors("rate_factors", rate_factors)
    concentration_factors = _factors("concentration_factors", concentration_factors)
    salinity_factors = _factors("salinity_factors", salinity_factors)
    (slug_size_factor,) = _factors("slug_size_factor", [slug_size_factor])
    (post_flush_pv,) = _factors("post_flush_pv", [post_flush_pv])
    chosen = DESIGN_KINDS if kinds is None else tuple(kinds)
    unknown = sorted(set(chosen) - set(DESIGN_KINDS))
    if unknown:
        raise ParameterError(f"design space: unknown kind(s) {unknown}; allowed {list(DESIGN_KINDS)}")

    slugs = list(sched.slugs)
    polymer = [i for i, s in enumerate(slugs) if s.polymer_ppm > 0.0]
    has_surfactant = any(s.surfactant_ppm > 0.0 for s in slugs)
    rate = [q0 if s.rate_ml_min is None else s.rate_ml_min for s in slugs]
    designs: list[Design] = []

    def add(kind: str, label: str, new: Sequence[Slug]):
        if kind in chosen:
            designs.append(Design(label, kind, _schedule(f"{sched.name}:{label}", new)))

    add("repeat", f"repeat {sched.name}", slugs)
    if polymer:
        last = polymer[-1]
        p = slugs[last]
        for f in concentration_factors:
            what = "polymer and surfactant" if has_surfactant else "polymer"
            add("concentration", f"{what} concentrations x{_fmt(f)}",
                [replace(s, polymer_ppm=s.polymer_ppm * f, surfactant_ppm=s.surfactant_ppm * f) for s in slugs])
        add("slug_size", f"polymer slug {p.name!r} x{_fmt(slug_size_factor)} in size ({_fmt(p.pv * slug_size_factor)} PV)",
            slugs[:last] + [replace(p, pv=p.pv * slug_size_factor)] + slugs[last + 1:])
        for f in salinity_factors:
            add("salinity", f"polymer slugs at x{_fmt(f)} salinity",
                [replace(s, salinity_ppm=s.salinity_ppm * f) if i in polymer else s for i, s in enumerate(slugs)])
        for f in rate_factors:
            add("rate_step", f"polymer slug {p.name!r}: second half at x{_fmt(f)} rate ({_fmt(rate[last] * f)} ml/min)",
                slugs[:last] + _split(p, [rate[last], rate[last] * f]) + slugs[last + 1:])
        if len(rate_factors) > 1:
            steps = [rate[last]] + [rate[last] * f for f in rate_factors]
            add("rate_step", f"polymer slug {p.name!r} as a rate staircase "
                f"({', '.join(_fmt(q) for q in steps)} ml/min)",
                slugs[:last] + _split(p, steps) + slugs[last + 1:])
    end = slugs[-1]
    longer = replace(end, pv=end.pv + post_flush_pv)
    add("post_flush", f"post-flush {end.name!r} extended by {_fmt(post_flush_pv)} PV", slugs[:-1] + [longer])
    steps = [rate[-1]] + [rate[-1] * f for f in rate_factors]
    add("post_flush_rate_step", f"post-flush {end.name!r} extended by {_fmt(post_flush_pv)} PV as a rate staircase "
        f"({', '.join(_fmt(q) for q in steps)} ml/min)", slugs[:-1] + _split(longer, steps))
    labels = [d.label for d in designs]
    if len(set(labels)) != len(labels):  # e.g. a factor given twice
        raise ParameterError(f"design space: duplicate designs {sorted({x for x in labels if labels.count(x) > 1})}")
    return designs
