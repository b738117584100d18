"""SP property sub-models as numba scalar kernels (UTCHEM forms; equation numbers refer to the seed MS thesis).

Every public function is ``@njit(cache=True)``, takes scalar floats (ints for flags) and returns a float or a tuple
of floats, so that the solver can call it from inside its own ``@njit`` time loop. No kernel raises or allocates;
parameter ranges are validated by the caller before any work.

Modules:

- ``effective_salinity``       -- polymer (Eq. 2.3) and phase-behaviour effective salinities.
- ``polymer_viscosity``        -- Flory-Huggins zero-shear polymer viscosity with salinity (Eqs. 2.1-2.2).
- ``shear_thinning``           -- Meter law (Eq. 2.4), concentration/salinity half-shear rate (Eq. 2.5),
                                  UTCHEM in-situ equivalent shear rate.
- ``permeability_reduction``   -- polymer permeability reduction R_k and its maximum (Eqs. 2.7-2.8).
- ``adsorption``               -- Langmuir adsorption of surfactant/polymer (Eqs. 2.15-2.16), retardation.
- ``phase_behaviour``          -- Hand's rule binodal, salinity interpolation, Winsor II(-)/III/II(+) flash,
                                  solubilization ratios.
- ``ift``                      -- Hirasaki correction (Eq. 2.10) and modified Chun-Huh IFT (Eq. 2.9).
- ``microemulsion_viscosity``  -- compositional phase viscosity (Eq. 2.11).
- ``trapping``                 -- trapping number, residual saturations (Eq. 2.12), end-point interpolation (Eq. 2.13).
- ``relative_permeability``    -- normalized saturation (Eqs. 1.7/2.14) and Corey law (Eqs. 1.6/2.14).
- ``capillary_pressure``       -- Brooks-Corey capillary pressure scaled with IFT (Eq. 1.8).
- ``dispersion``               -- 1-D longitudinal dispersion coefficient (Eq. 1.9).
"""
