"""Row layout of the kernel's per-cell arrays (module-level integers: compile-time constants for numba).

State ``st[NST, cells]`` -- what the time loop carries from step to step, in pore-volume units (per pore volume of
the cell):

- ``M1, M2``: water and oil volume; ``M3``: surfactant volume, fluid plus adsorbed (``EPHI3 C3 + C^3``);
  ``M4``: polymer, fluid plus adsorbed (``EPHI4 S_c C4 + C^4``, wt % x PV); ``M5, M6``: anions and divalent cations
  carried by the water (meq/ml x water volume);
- ``A3, A4``: adsorbed surfactant / polymer (running maxima: irreversible in concentration);
- ``RK``: permeability-reduction factor, evaluated at ``CPMAX``, the running maximum of the polymer concentration
  in the cell (irreversible);
- ``FPC``: fractional flow of the polymer-carrying phase at the previous step (lagged shear rate);
- ``GRADK``: ``k |dp/dx| = u / lambda_T`` (Pa) at the previous step (lagged trapping number).

Properties ``pr[NPR, cells]`` -- recomputed from the state at the start of every step (see ``cell_properties``).
"""

M1, M2, M3, M4, M5, M6, A3, A4, RK, CPMAX, FPC, GRADK = range(12)
NST = 12

S1 = 0  # saturations S1, S2, S3 at S1 + l - 1
F1 = 3  # fractional flows f1, f2, f3
C2P = 6  # oil fraction of phase l at C2P + l - 1
C3P = 9  # surfactant fraction of phase l at C3P + l - 1
CP, PCX, C5, C6, LAMT, SPEED, KW, KS, KP, PCAP, LWO, DCAP, SPC, PTYPE, FW, WAVE = range(12, 28)
V1 = 28  # interstitial velocity f_l / S_l of phase l at V1 + l - 1 (PV units)
IFT = 31  # largest IFT between the ME and an excess phase present (oil-water without ME; 0 single ME), mN/m
NPR = 32

# error codes returned by the kernel
OK = 0
ERR_COLLAPSE = 1
ERR_NONFINITE = 2
ERR_IMMOBILE = 3
