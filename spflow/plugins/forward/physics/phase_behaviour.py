"""Surfactant/brine/oil phase behaviour: Hand's rule binodal and a Winsor II(-)/III/II(+) flash (UTCHEM, IFGHBN = 0).

Pseudo-ternary water (1) / oil (2) / surfactant (3) in volume fractions; salinities in meq/ml. Phases: 1 aqueous
(excess water), 2 oleic (excess oil), 3 microemulsion (ME). Thesis section 2.5 and UTCHEM-9.0 Technical Documentation
§2; docs/forward_model.md, Property values.

Binodal (Hand's rule, B = -1): ``C3^2 = A C1 C2``. Writing ``w = C2 / (C1 + C2)`` and ``q = sqrt(A w (1 - w))``,
the binodal point at normalised oil fraction ``w`` is ``(1 - w, w, q) / (1 + q)``; its maximum height (``w = 1/2``)
is ``C3max`` when ``A = (2 C3max / (1 - C3max))^2``. The two-phase (and three-phase) region is the inside of this
ellipse, ``z3^2 < A z1 z2``; on or above it the mixture is a single ME phase.

Tie-lines (plait points at the apices, C2PRC = 0 / C2PLC = 1, as in thesis Table 2.4):

- Type II(-), ``C_SE < CSEL``: every tie-line passes through the oil apex O = (0, 1, 0). The ME (reported as phase 3,
  the water-rich lower phase) lies where the ray from O through ``z`` meets the binodal; excess oil is pure oil
  (phase 2) and ``s1 = 0``. With ``D = z3^2 + A z1 (z1 + z3)``: ME = ``(A z1^2, z3^2, A z1 z3) / D``, ME fraction
  ``D / (A z1)`` and excess oil ``(A z1 z2 - z3^2) / (A z1)`` -- the closed form of docs/forward_model.md, Property
  values
  (``t = A z1 / (z3^2 + A z1 (1 - z2))``, ME = ``(t z1, 1 + t (z2 - 1), t z3)``, ME fraction ``1/t``) rearranged so
  that no term cancels.
- Type II(+), ``C_SE > CSEU``: the mirror image -- tie-lines through the water apex W = (1, 0, 0), oil-rich ME
  (phase 3), pure excess water (phase 1), ``s2 = 0``.
- Type III, ``CSEL <= C_SE <= CSEU``: invariant point M on the binodal with ``w_M = (C_SE - CSEL)/(CSEU - CSEL)``.
  Inside the triangle (W, O, M) the lever rule gives pure excess water, pure excess oil and ME = M. The two-phase lobe
  beyond the chord O-M (oil side) has tie-lines through O (II(-)-like: ME + excess oil); the lobe beyond the chord
  W-M (water side) has tie-lines through W (II(+)-like: ME + excess water). Tie-lines through the opposite apex would
  cross the three-phase triangle, so each lobe uses the apex that bounds it.

Continuity: at ``C_SE = CSEL`` the invariant point is W, the triangle and the water lobe vanish and the type III
split equals the type II(-) split (likewise at CSEU with II(+)); across the chords O-M and W-M the lobe tie-line ends
at M with the same fractions as the lever rule; on the binodal the excess-phase fraction is 0. The ME is always
phase 3, so the only jumps are in the ``phase_type`` label and at the CMC: for ``z3 < EPSME`` (or ``z3 <= 0``) no ME
forms and all the surfactant stays in the aqueous phase 1 beside pure oil (phase_type 0), so the water-rich phase
changes index from 3 to 1 as ``z3`` drops below EPSME.

Absent phases are reported with saturation 0 and a reference composition: aqueous (1, 0, 0), oleic (0, 1, 0), and for
the ME absent below the CMC the composition of the aqueous phase. Saturations and compositions are always in [0, 1]
and the component volume balance ``sum_l s_l C_kl = z_k`` holds to round-off.
"""

import math

from numba import njit

NO_MICROEMULSION = 0
TYPE_II_MINUS = 1
TYPE_III = 2
TYPE_II_PLUS = 3


@njit(cache=True, error_model="numpy")
def hand_a(c3max):
    """Hand's-rule parameter ``A = (2 C3max / (1 - C3max))^2`` from the binodal height ``C3max`` (vol. fraction)."""
    r = 2.0 * c3max / (1.0 - c3max)
    return r * r


@njit(cache=True, error_model="numpy")
def hand_a_salinity(cse, csel, cseu, c3max0, c3max1, c3max2):
    """Hand's ``A`` at effective salinity ``cse`` (meq/ml), linear in ``C_SE / C_SEOP`` (UTCHEM-9.0 Technical
    Documentation §2).

    ``A_m = hand_a(C3max,m)`` for the binodal heights at zero (m = 0, HBNC70), optimal (1, HBNC71) and twice-optimal
    (2, HBNC72) salinity; ``C_SEOP = (CSEL + CSEU)/2``;
    ``A = (A0 - A1)(1 - C_SE/C_SEOP) + A1`` for ``C_SE <= C_SEOP``, ``A = (A2 - A1)(C_SE/C_SEOP - 1) + A1`` above.
    Extrapolation beyond ``2 C_SEOP`` with ``A2 < A1`` would give a negative A (a binodal of imaginary height), so the
    result is floored at 0.
    """
    cseop = 0.5 * (csel + cseu)
    a1 = hand_a(c3max1)
    ratio = cse / cseop
    if ratio <= 1.0:
        a = (hand_a(c3max0) - a1) * (1.0 - ratio) + a1
    else:
        a = (hand_a(c3max2) - a1) * (ratio - 1.0) + a1
    return a if a > 0.0 else 0.0


@njit(cache=True, error_model="numpy")
def _apex_split(z_me, z_apex, z3, a):
    """Split ``z`` on the tie-line through the apex of the excess component (inside the binodal, ``a z_me > 0``).

    ``z_me`` is the fraction of the component the ME is rich in, ``z_apex`` that of the excess pure component.
    Uses the module-docstring closed form divided through by ``z_me`` (``p = z3^2 / z_me``, ``d = p + a (z_me + z3)``)
    so that nothing underflows for tiny ``z_me``; the fractions are clipped to [0, 1] against round-off near the
    binodal. Returns ``(s_me, s_excess, c_me_rich, c_me_apex, c_me_3)``.
    """
    p = z3 * z3 / z_me
    d = p + a * (z_me + z3)
    s_me = d / a
    s_excess = z_apex - p / a
    return min(s_me, 1.0), max(s_excess, 0.0), a * z_me / d, p / d, a * z3 / d


@njit(cache=True, error_model="numpy")
def _split_excess_oil(phase_type, z1, z2, z3, a):
    """ME + excess oil on the tie-line through the oil apex; returns the flash tuple."""
    s3, s2, c13, c23, c33 = _apex_split(z1, z2, z3, a)
    return phase_type, 0.0, s2, s3, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, c13, c23, c33


@njit(cache=True, error_model="numpy")
def _split_excess_water(phase_type, z1, z2, z3, a):
    """ME + excess water on the tie-line through the water apex; returns the flash tuple."""
    s3, s1, c23, c13, c33 = _apex_split(z2, z1, z3, a)
    return phase_type, s1, 0.0, s3, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, c13, c23, c33


@njit(cache=True, error_model="numpy")
def flash(z1, z2, z3, cse, csel, cseu, c3max0, c3max1, c3max2, epsme):
    """Phase split of the overall volume fractions ``(z1, z2, z3)`` (summing to 1) at effective salinity ``cse``.

    ``csel``, ``cseu`` (meq/ml) bound the type III window; ``c3max0..2`` are the binodal heights HBNC70..72;
    ``epsme`` is the CMC (volume fraction). See the module docstring for the construction.

    Returns ``(phase_type, s1, s2, s3, c11, c21, c31, c12, c22, c32, c13, c23, c33)``: ``phase_type`` is 0 (no ME,
    ``z3 < epsme``), 1 (II(-)), 2 (III) or 3 (II(+)) -- the salinity type, also when the mixture is a single ME phase
    (then ``s3 = 1``); ``s_l`` are phase volume fractions (sum 1) and ``c_kl`` the volume fraction of component k in
    phase l (each phase sums to 1).
    """
    if z3 < epsme or z3 <= 0.0:
        aqueous = z1 + z3
        if aqueous > 0.0:
            c11 = z1 / aqueous
            c31 = z3 / aqueous
        else:
            c11 = 1.0
            c31 = 0.0
        return NO_MICROEMULSION, aqueous, z2, 0.0, c11, 0.0, c31, 0.0, 1.0, 0.0, c11, 0.0, c31

    if cse < csel:
        phase_type = TYPE_II_MINUS
    elif cse > cseu:
        phase_type = TYPE_II_PLUS
    else:
        phase_type = TYPE_III
    a = hand_a_salinity(cse, csel, cseu, c3max0, c3max1, c3max2)

    if z3 * z3 >= a * z1 * z2:
        return phase_type, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, z1, z2, z3
    if phase_type == TYPE_II_MINUS:
        return _split_excess_oil(phase_type, z1, z2, z3, a)
    if phase_type == TYPE_II_PLUS:
        return _split_excess_water(phase_type, z1, z2, z3, a)

    width = cseu - csel
    w = (cse - csel) / width if width > 0.0 else 0.5
    q = math.sqrt(a * w * (1.0 - w))
    if q <= 0.0:  # invariant point at an apex (C_SE = CSEL or CSEU): the three-phase triangle is degenerate
        if w < 0.5:
            return _split_excess_oil(phase_type, z1, z2, z3, a)
        return _split_excess_water(phase_type, z1, z2, z3, a)
    c1m = (1.0 - w) / (1.0 + q)
    c2m = w / (1.0 + q)
    c3m = q / (1.0 + q)
    s3 = z3 / c3m
    s1 = z1 - s3 * c1m
    s2 = z2 - s3 * c2m
    if s1 >= 0.0 and s2 >= 0.0:
        return phase_type, s1, s2, min(s3, 1.0), 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, c1m, c2m, c3m
    if s1 < s2:
        return _split_excess_oil(phase_type, z1, z2, z3, a)
    return _split_excess_water(phase_type, z1, z2, z3, a)


@njit(cache=True, error_model="numpy")
def solubilization_ratios(c13, c23, c33):
    """Solubilization ratios ``(R13, R23) = (C13 / C33, C23 / C33)`` of the ME; ``(0, 0)`` when ``C33 <= 0`` (no
    surfactant: the Chun-Huh IFT then falls back to the oil-water value)."""
    if c33 <= 0.0:
        return 0.0, 0.0
    return c13 / c33, c23 / c33
