"""OPM Flow's time steps on an exported coreflood: the default cap and the TUNING keyword that sets it.

OPM Flow chooses its own steps, up to a report step, and its fully implicit first-order scheme then carries a time
error far above a lab's noise (docs/opm.md, *OPM's time error, and the cap*). An exported deck caps the steps of
every slug at a fraction of that slug's pore-volume time with a TUNING keyword (:func:`tuning_keyword`), which OPM
honours only when run with :data:`TUNING_OPTION`. No heavy imports: the command line reads the default from here.
"""

from __future__ import annotations

__all__ = ["DEFAULT_MAX_STEP_PV", "TUNING_OPTION", "tuning_keyword"]

#: default cap on OPM's time steps, in PV of the slug being injected: the pre-breakthrough pressure drop of a
#: polymer flood (0.8 PV water, 0.5 PV of 2500 ppm, chase water; 100 blocks, 0.01 PV report steps) at 0.3 PV reads
#: 9406 Pa with OPM's own steps and 8983 / 8858 / 8785 / 8746 Pa with steps capped at 0.004 / 0.002 / 0.001 / 0.0005
#: PV (first order in the step, limit about 8707 Pa): at 0.0005 PV the time error is about 0.5 %, below a
#: transducer's 2 % noise, at 2-4x the run time of OPM's own steps
DEFAULT_MAX_STEP_PV = 0.0005
#: the option that makes OPM honour the deck's TUNING keywords; given to a deck whose steps are capped and not to
#: others, where it would replace flow's own step-control settings by ECLIPSE's TUNING defaults
TUNING_OPTION = "--enable-tuning=true"
#: TUNING's TSFMIN, which OPM Flow 2022.10 reads as its smallest time step in seconds (:func:`tuning_keyword`)
_MIN_STEP_S = 1.0e-7


def tuning_keyword(max_step_days: float) -> str:
    """The TUNING keyword of a capped slug. Record 1: TSINIT and TSMAXZ the cap (days); TSFMAX 3, TSFCNV 0.33 and
    TFDIFF 2, flow's own defaults for the growth limit, the chop factor and the growth factor (under TUNING its
    command-line options give way to ECLIPSE's defaults 3, 0.1 and 1.25); TSFMIN ``_MIN_STEP_S``, because OPM Flow
    2022.10 takes TSFMIN (ECLIPSE's minimum chop factor, 0.3) as its smallest time step in seconds and stops at the
    first step chopped below 0.3 s, which capped steps reach where a polymer slug starts. Records 2 and 3
    defaulted."""
    cap = f"{max_step_days:.10g}"
    return f"TUNING\n  {cap} {cap} 1* 1* 3 {_MIN_STEP_S:g} 0.33 2 /\n/\n/\n"
