"""Oracle inputs expressed as the simulator's UTCHEM input names (the contract of ``simulate(params=...)``).

Only names are mapped here -- no simulator code is imported. Low-capillary-number Corey curves map to
``S1RWC, S2RWC`` (residuals), ``P1RWC, P2RWC`` (end points), ``E1WC, E2WC`` (exponents), ``VIS1, VIS2`` (cP); the
microemulsion residual ``S3RWC`` is set to 0 so that the two-phase normalisation ``1 - S_wc - S_or`` applies.
"""


def corey_params(flux, s_init: float | None = None) -> dict:
    """UTCHEM parameters reproducing ``flux`` (a :class:`oracles.corey.CoreyFractionalFlow`) with ``SWI = s_init``
    (default ``S_wc``)."""
    return {
        "SWI": flux.swc if s_init is None else s_init,
        "S1RWC": flux.swc,
        "S2RWC": flux.sor,
        "S3RWC": 0.0,
        "P1RWC": flux.krw0,
        "P2RWC": flux.kro0,
        "E1WC": flux.nw,
        "E2WC": flux.no,
        "VIS1": flux.mu_w,
        "VIS2": flux.mu_o,
    }
