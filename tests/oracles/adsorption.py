"""Langmuir retardation of a chemical step (UTCHEM-9.0 Technical Documentation §2; thesis Eqs. 2.15-2.16).

``C_hat = a C / (1 + b C)`` (adsorbed volume per pore volume); a step from 0 to ``C_J`` is retarded by
``D = C_hat(C_J)/C_J = a/(1 + b C_J)`` pore volumes (UTCHEM units: ``a`` dimensionless, ``b`` per unit of ``C``).
"""


def langmuir_retardation(a: float, b: float, c_injected: float) -> float:
    """Retardation ``D = a/(1 + b C_J)`` in PV units for a Langmuir isotherm (``a``, ``b`` >= 0, ``C_J`` > 0)."""
    if not a >= 0.0:
        raise ValueError(f"a (Langmuir capacity) must be >= 0, got {a}")
    if not b >= 0.0:
        raise ValueError(f"b (Langmuir constant) must be >= 0, got {b}")
    if not c_injected > 0.0:
        raise ValueError(f"c_injected must be > 0, got {c_injected}")
    return a / (1.0 + b * c_injected)
