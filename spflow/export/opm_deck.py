"""Write a self-contained ECLIPSE deck (OPM Flow, METRIC units) of a 1-D spflow coreflood.

The core becomes a row of ``cells`` grid blocks along x. A true-size core breaks OPM's well model (a fixed well-bore
pseudo-volume and field-sized well tolerances), so the cross-section and the injection rate are scaled up together
by ``area_scale``: the Darcy velocity, the pressure drop and every per-pore-volume quantity are unchanged, and only
the volumes and rates of the summary carry the factor (the scaling is printed and stored in :class:`OpmDeck`).

Wells: the injector sits in the first block (water rate and WPOLYMER concentration per slug: a slug's
``rate_ml_min`` or QINJ, scaled like the cross-section), the producer in the last one (bottom-hole pressure).
Their connection transmissibility factors are those of half a block, so the injector and producer BHPs are the
pressures of the inlet and outlet faces and ``BHP_inj - BHP_prod`` is the pressure drop across the core as spflow
computes it. Initial state: water at ``SWI``, pressure the steady flow profile of the initial fluids at the first
slug's rate above the producer pressure (a uniform pressure equal to the producer BHP stalls OPM's first Newton step).
Water and oil are nearly incompressible (1e-7 1/bar); rock compressibility 1e-8 1/bar.

Time steps: the deck caps OPM's at ``max_step_pv`` (default ``DEFAULT_MAX_STEP_PV``) of each slug's pore-volume
time with a TUNING keyword per slug (:mod:`.opm_time_steps`), which OPM honours only when run with
``--enable-tuning=true`` (:func:`~.opm_run.run_opm` passes it; the header says so).

Mechanisms OPM cannot express are refused or approximated (:mod:`.opm_mechanisms`); the tables are
:mod:`.opm_tables`, shear thinning (PLYSHLOG and the wells' bore diameter) :mod:`.opm_shear`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from spflow.core.errors import ParameterError
from spflow.plugins.forward import effects as E
from spflow.plugins.forward import units
from spflow.plugins.forward.checks import check_number
from spflow.plugins.forward.parameters import resolve_params
from spflow.plugins.forward.schedule import as_schedule

from .opm_mechanisms import check_mechanisms, refuse_or_note
from .opm_shear import SECONDS_PER_DAY, OpmShear, matching_bore_diameter, opm_shear
from .opm_tables import KG_M3_PER_PPM, PA_PER_BAR, OpmTables, opm_tables
from .opm_time_steps import DEFAULT_MAX_STEP_PV, tuning_keyword

__all__ = ["OpmDeck", "write_opm_deck", "DARCY_METRIC", "DEFAULT_AREA_M2", "DEFAULT_MAX_STEP_PV"]

#: Darcy constant of OPM's METRIC units: T [cP rm3/day/bar] = DARCY_METRIC k [mD] A [m2] / L [m]
DARCY_METRIC = 0.00852702
#: default scaled cross-section (m2): with 1 m2 the producer's well-bore storage (0.1 ft3) still lags the produced
#: oil cut by ~0.02 at the first 0.01 PV of a core flood; 1e4 m2 makes it < 1e-6 (measured on a Corey waterflood)
DEFAULT_AREA_M2 = 1.0e4
_PRODUCER_BHP_BAR = 200.0
_COMPRESSIBILITY = 1.0e-7  # 1/bar, water and oil
_ROCK_COMPRESSIBILITY = 1.0e-8  # 1/bar


@dataclass(frozen=True)
class OpmDeck:
    """A written deck and what a reader of its results needs (volumes of the scaled model, slug times)."""

    path: Path
    cells: int
    area_scale: float  # scaled cross-section / core cross-section (= scaled rate / core rate)
    pore_volume_m3: float  # of the scaled model
    slug_rate_m3_day: np.ndarray  # per slug, of the scaled model
    slug_pv_time_days: np.ndarray  # per slug, time to inject one pore volume
    max_step_pv: float | None  # cap on OPM's time steps (PV of the slug injected; TUNING), None: OPM's own steps
    report_pv: np.ndarray  # injected PV at the end of every report step
    tables: OpmTables
    notes: list[str] = field(default_factory=list)
    experiment: str = "custom"
    params: dict[str, float] = field(default_factory=dict)  # the resolved forward-model parameters
    schedule: object = None  # the validated Schedule
    shear: OpmShear | None = None  # PLYSHLOG, when shear thinning is exported


def _fmt(x: float) -> str:
    return f"{x:.10g}"


def _table(rows) -> str:
    return "\n".join("  " + " ".join(_fmt(v) for v in row) for row in rows) + " /\n"


def _report_steps(sched, pv_step: float) -> tuple[list[list[float]], np.ndarray]:
    """Per slug the report-step sizes (PV) no longer than ``pv_step``, and the cumulative PV of every step."""
    steps, ends, t = [], [], 0.0
    for slug in sched.slugs:
        n = max(1, math.ceil(slug.pv / pv_step - 1e-9))
        steps.append([slug.pv / n] * n)
        for _ in range(n):
            t += slug.pv / n
            ends.append(t)
    return steps, np.array(ends)


def _resolve(schedule, params, effects):
    sched = as_schedule(schedule)
    p = resolve_params(params)
    registry = E.default_registry()
    s = registry.resolve(effects)
    foreign = [n for n, v in s.items() if n not in E.BUILTIN_NAMES and v != 0.0]
    return sched, p, s, foreign


def _initial_pressure(p, tables, x_m, length_m, rate_ml_min) -> np.ndarray:
    """Steady pressures (bar) of the initial fluids at ``rate_ml_min`` at the block centres ``x_m`` above the
    producer: a gradient, not a flat field at the producer BHP."""
    sw = tables.swof[:, 0]
    krw = np.interp(p["SWI"], sw, tables.swof[:, 1])
    kro = np.interp(p["SWI"], sw, tables.swof[:, 2])
    lam = krw / (p["VIS1"] * units.CP_TO_PA_S) + kro / (p["VIS2"] * units.CP_TO_PA_S)
    u = rate_ml_min * units.ML_MIN_TO_M3_S / (math.pi * p["DIAMETER"] ** 2 / 4.0)
    grad = u / (p["PERM"] * units.MD_TO_M2 * max(lam, 1e-12)) / PA_PER_BAR  # bar/m
    return _PRODUCER_BHP_BAR + grad * (length_m - x_m)


def write_opm_deck(path, schedule, params=None, effects=None, cells: int = 100, *, approximate: bool = False,
                   area_scale: float | None = None, pv_step: float = 0.01, rock_density: float = 2650.0,
                   swof_nodes: int = 401, polymer_nodes: int = 201, shear_sw: float | None = None,
                   max_step_pv: float | None = DEFAULT_MAX_STEP_PV, provenance=(), log=print) -> OpmDeck:
    """Write the OPM Flow deck of one coreflood to ``path`` (a ``.DATA`` file; its directory is created).

    ``schedule``, ``params`` and ``effects`` are those of :func:`spflow.simulate`. ``area_scale`` multiplies the
    core cross-section and the rate (default: a ``DEFAULT_AREA_M2`` = 1e4 m2 cross-section); ``pv_step`` is the
    report (and summary) interval in PV; ``rock_density`` (kg/m3) converts the adsorption to OPM's kg/kg rock.
    Mechanisms OPM cannot express raise :class:`~.opm_mechanisms.OpmExportError` (a ``ParameterError``) naming
    them, unless ``approximate`` -- then each approximation is printed through ``log`` and kept in
    ``OpmDeck.notes``. ``shear_sw`` is the water saturation at which OPM's shear rate is matched to spflow's in a
    two-phase core (default ``1 - S2RWC``; :mod:`.opm_shear`). ``max_step_pv`` caps OPM's time steps at that
    fraction of each slug's pore-volume time (a TUNING keyword per slug; ``None``: OPM's own step control, whose time
    error is large, see the module docstring). ``provenance``: text lines (where each value came
    from, :func:`~spflow.export.opm_model.export_opm`) written into the header as comments.
    """
    if isinstance(cells, bool) or not isinstance(cells, (int, np.integer)) or not 3 <= cells <= 100000:
        raise ParameterError(f"cells must be an integer in [3, 100000], got {cells!r}")
    cells = int(cells)
    sched, p, s, foreign = _resolve(schedule, params, effects)
    pv_step = check_number("pv_step", pv_step, 0.0, sched.total_pv, lower_open=True)
    if max_step_pv is not None:
        max_step_pv = check_number("max_step_pv", max_step_pv, 0.0, 1.0, lower_open=True)
    rock_density = check_number("rock_density (kg/m3)", rock_density, 500.0, 10000.0)
    if shear_sw is not None:
        shear_sw = check_number("shear_sw", shear_sw, p["S1RWC"], 1.0, lower_open=True)
    found = check_mechanisms(sched, p, s, shear_sw)
    notes = refuse_or_note(found, approximate, log)
    if foreign:
        if not approximate:
            raise ParameterError(f"effects {foreign} are plugin effects with non-zero strength; OPM Flow cannot "
                                 "express them (set their strength to 0 or pass approximate=True)")
        notes.append(f"APPROXIMATION plugin effects {foreign} dropped")
        log(notes[-1])
    tables = opm_tables(sched, p, s, rock_density=rock_density, swof_nodes=swof_nodes, polymer_nodes=polymer_nodes)
    shear = opm_shear(sched, p, s, tables, shear_sw=shear_sw)

    core_area = math.pi * p["DIAMETER"] ** 2 / 4.0
    if area_scale is None:
        area_scale = DEFAULT_AREA_M2 / core_area
    area_scale = check_number("area_scale", area_scale, 1.0, 1.0e9)
    area = core_area * area_scale
    side = math.sqrt(area)
    length = p["LENGTH"]
    dx = length / cells
    pore_volume = p["PORO"] * area * length
    rates_ml_min = sched.rates_ml_min(p["QINJ"])
    rates = rates_ml_min * units.ML_MIN_TO_M3_S * area_scale * SECONDS_PER_DAY
    t_pv = pore_volume / rates
    rate_text = (f"rate {p['QINJ']:g} ml/min" if not sched.has_rates else
                 f"slug rates {', '.join(f'{q:g}' for q in rates_ml_min)} ml/min")
    scaling = (f"OPM deck: core cross-section {core_area * 1e4:.4g} cm2 and {rate_text} scaled by {area_scale:.6g} to "
               f"{area:.4g} m2 and {', '.join(f'{r:.6g}' for r in rates)} m3/day (Darcy velocity, pressure drop and "
               f"per-PV quantities unchanged); {cells} blocks of {dx * 1e3:.4g} mm; 1 PV = "
               f"{', '.join(f'{t:.6g}' for t in t_pv)} days")
    log(scaling)
    notes.insert(0, scaling)
    if max_step_pv is None:
        stepping = ("OPM deck: no cap on OPM's time steps (OPM's own step control, up to a report step of "
                    f"{pv_step:g} PV: its time error can exceed a lab's noise)")
    else:
        stepping = (f"OPM deck: time steps capped at {max_step_pv:g} PV = "
                    f"{', '.join(f'{max_step_pv * t:.6g}' for t in t_pv)} days per slug (TUNING TSMAXZ; run flow with "
                    "--enable-tuning=true)")
    log(stepping)
    notes.insert(1, stepping)

    x = (np.arange(cells) + 0.5) * dx
    pressure = _initial_pressure(p, tables, x, length, rates_ml_min[0])
    half_block_cf = DARCY_METRIC * p["PERM"] * area / (0.5 * dx)
    bore = "1*"  # OPM's default 1 ft
    if shear is not None:
        diameter = matching_bore_diameter(dx, side)
        bore = _fmt(diameter)
        shear_note = (f"OPM deck: shear thinning as PLYSHLOG ({shear.table.shape[0]} water velocities, reference "
                      f"{shear.c_ref:g} kg/m3, half shear rate {shear.gamma_half:.6g} 1/s), spflow's shear rate = "
                      f"{shear.rate_per_velocity:.6g} 1/m x OPM's water velocity at Sw* = {shear.reference_sw:g} "
                      f"(Swcr = {shear.swcr:g}); well-bore diameter {diameter:.6g} m gives the wells' connections "
                      "the blocks' water velocity")
        log(shear_note)
        notes.insert(2, shear_note)
    steps, report_pv = _report_steps(sched, pv_step)
    has_polymer = any(sl.polymer_ppm > 0.0 for sl in sched.slugs)

    out = []
    w = out.append
    w(f"-- spflow export of coreflood {sched.name!r} to OPM Flow (METRIC units)\n")
    for line in provenance:
        w(f"-- {line}\n")
    for note in notes:
        w(f"-- {note}\n")
    w("RUNSPEC\nTITLE\n  spflow coreflood {}\n".format(sched.name))
    w(f"DIMENS\n  {cells} 1 1 /\nOIL\nWATER\n")
    w("POLYMER\n")
    w("METRIC\n")
    n_sat = tables.swof.shape[0]
    n_ply = tables.plyvisc.shape[0]
    w(f"TABDIMS\n  1 1 {max(n_sat, n_ply)} {max(n_ply, 20)} /\n")
    w("WELLDIMS\n  2 1 1 2 /\nSTART\n  1 JAN 2000 /\nUNIFOUT\n")

    w("GRID\n")
    w(f"DX\n  {cells}*{_fmt(dx)} /\nDY\n  {cells}*{_fmt(side)} /\nDZ\n  {cells}*{_fmt(side)} /\n")
    w(f"TOPS\n  {cells}*1000 /\nPORO\n  {cells}*{_fmt(p['PORO'])} /\n")
    for k in ("PERMX", "PERMY", "PERMZ"):
        w(f"{k}\n  {cells}*{_fmt(p['PERM'])} /\n")

    w("PROPS\n")
    w(f"-- water and oil viscosities VIS1, VIS2 (cP); compressibility {_COMPRESSIBILITY:g} 1/bar\n")
    w(f"PVTW\n  {_fmt(_PRODUCER_BHP_BAR)} 1.0 {_COMPRESSIBILITY:g} {_fmt(p['VIS1'])} 0.0 /\n")
    b_hi = math.exp(-_COMPRESSIBILITY * (1000.0 - _PRODUCER_BHP_BAR))
    b_lo = math.exp(_COMPRESSIBILITY * (_PRODUCER_BHP_BAR - 1.0))
    w(f"PVDO\n  1.0 {_fmt(b_lo)} {_fmt(p['VIS2'])}\n  {_fmt(_PRODUCER_BHP_BAR)} 1.0 {_fmt(p['VIS2'])}\n"
      f"  1000.0 {_fmt(b_hi)} {_fmt(p['VIS2'])} /\n")
    w("DENSITY\n  800.0 1000.0 1.0 /\n")
    w(f"ROCK\n  {_fmt(_PRODUCER_BHP_BAR)} {_ROCK_COMPRESSIBILITY:g} /\n")
    w("-- SWOF: low-Nc Corey curves (Eqs. 1.6-1.7, 2.14): Sw krw krow Pcow(bar)\nSWOF\n")
    w(_table(tables.swof))
    w(f"-- PLYVISC: Flory-Huggins viscosity multiplier (Eqs. 2.1-2.3) at {tables.salinity_ppm:g} ppm "
      f"(C_SEP = {tables.csep:.6g} meq/ml): c (kg/m3) mu_p/mu_w\nPLYVISC\n")
    w(_table(tables.plyvisc))
    w("-- PLYADS: Langmuir adsorption (Eqs. 2.15-2.16): c (kg/m3) adsorbed (kg/kg rock)\nPLYADS\n")
    w(_table(tables.plyads))
    w("-- PLYROCK: dead pore space (1 - EPHI4), RRF, rock density (kg/m3), adsorption index (2: irreversible), "
      "max adsorption (kg/kg)\nPLYROCK\n")
    w(f"  {_fmt(tables.dead_pore_space)} {_fmt(tables.rrf)} {_fmt(tables.rock_density)} {tables.adsorption_index} "
      f"{_fmt(tables.max_adsorption)} /\n")
    w(f"PLYMAX\n  {_fmt(tables.c_max)} /\n")
    w("-- full Todd-Longstaff mixing: the polymer moves with the water at the mixture viscosity\nPLMIXPAR\n  1.0 /\n")
    if shear is not None:
        w(f"-- PLYSHLOG: shear thinning (Meter, Eq. 2.4, at UTCHEM's equivalent shear rate gamma = "
          f"{shear.rate_per_velocity:.6g} 1/m x the water velocity at Sw* = {shear.reference_sw:g}): reference polymer "
          "concentration (kg/m3); water velocity (m/day) mu_p(gamma) / mu_p0 at it\n"
          f"PLYSHLOG\n  {_fmt(shear.c_ref)} /\n")
        w(_table(shear.table))

    w("SOLUTION\n")
    w(f"SWAT\n  {cells}*{_fmt(p['SWI'])} /\n")
    w("PRESSURE\n" + "".join(f"  {_fmt(v)}\n" for v in pressure) + " /\n")
    w(f"SPOLY\n  {cells}*0.0 /\n")

    w("SUMMARY\nRPTONLY\nFOPT\nFWPT\nFWIT\nFOIP\nWBHP\n  'INJ' 'PROD' /\nWCPT\n  'PROD' /\nWCIT\n  'INJ' /\n")

    w("SCHEDULE\n")
    w("WELSPECS\n  'INJ' 'G' 1 1 1* WATER /\n  'PROD' 'G' {} 1 1* OIL /\n/\n".format(cells))
    w(f"COMPDAT\n  'INJ' 1 1 1 1 OPEN 1* {_fmt(half_block_cf)} {bore} /\n"
      f"  'PROD' {cells} 1 1 1 OPEN 1* {_fmt(half_block_cf)} {bore} /\n/\n")
    w(f"WCONPROD\n  'PROD' OPEN BHP 5* {_fmt(_PRODUCER_BHP_BAR)} /\n/\n")
    for slug, sizes, rate, t_slug_pv in zip(sched.slugs, steps, rates, t_pv):
        w(f"-- slug {slug.name!r}: {slug.pv:g} PV, {slug.polymer_ppm:g} ppm polymer\n")
        w(f"WCONINJE\n  'INJ' WATER OPEN RATE {_fmt(rate)} 1* 10000 /\n/\n")
        if max_step_pv is not None:
            w(tuning_keyword(max_step_pv * t_slug_pv))
        if has_polymer:
            w(f"WPOLYMER\n  'INJ' {_fmt(slug.polymer_ppm * KG_M3_PER_PPM)} 0.0 /\n/\n")
        w("TSTEP\n  " + " ".join(_fmt(d * t_slug_pv) for d in sizes) + " /\n")
    w("END\n")

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("".join(out))
    return OpmDeck(path=path, cells=cells, area_scale=area_scale, pore_volume_m3=pore_volume, slug_rate_m3_day=rates,
                   slug_pv_time_days=t_pv, max_step_pv=max_step_pv, report_pv=report_pv, tables=tables, notes=notes,
                   experiment=sched.name, params=dict(p), schedule=sched, shear=shear)
