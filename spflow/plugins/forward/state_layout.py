"""Row layout of the kernel's per-cell arrays (module-level integers: compile-time constants for numba).

State ``st[NST, cells]`` -- what the time loop carries from step to step, in pore-volume units (per pore volume of
the cell):

- ``M1, M2``: water and oil volume; ``M3``: surfactant volume, fluid plus adsorbed (``EPHI3 C3 + C^3``);
  ``M4``: polymer, fluid plus adsorbed (``EPHI4 S_c C4 + C^4``, wt % x PV); ``M5, M6``: anions and divalent cations
  carried by the water (meq/ml x water volume);
- ``A3, A4``: adsorbed surfactant / polymer (running maxima: irreversible in concentration; polymer partly or
  fully reversible with ``kernel_inputs.REV4 > 0``);
- ``RK``: permeability-reduction factor, evaluated at ``CPMAX``, the running maximum of the polymer concentration
  in the cell (irreversible);
- ``FPC``: fractional flow of the polymer-carrying phase at the previous step (lagged shear rate);
- ``GRADK``: ``k |dp/dx| = u / lambda_T`` (Pa) at the previous step (lagged trapping number);
- ``A4I``: the irreversible part of the adsorbed polymer (a running maximum) when a fraction of the polymer
  adsorption is reversible (``kernel_inputs.REV4 > 0``; then ``A4`` is not a running maximum); unused otherwise.

Properties ``pr[NPR, cells]`` -- recomputed from the state at the start of every step (see ``cell_properties``);
the rows from ``C1P`` on also carry values between the three property passes (rel-perm inputs and results).
"""

M1, M2, M3, M4, M5, M6, A3, A4, RK, CPMAX, FPC, GRADK, A4I = range(13)
NST = 13

S1 = 0  # saturations S1, S2, S3 at S1 + l - 1
F1 = 3  # fractional flows f1, f2, f3
C2P = 6  # oil fraction of phase l at C2P + l - 1
C3P = 9  # surfactant fraction of phase l at C3P + l - 1
CP, PCX, C5, C6, LAMT, SPEED, KW, KS, KP, PCAP, LWO, DCAP, SPC, PTYPE, WAVE = range(12, 27)
V1 = 27  # interstitial velocity f_l / S_l of phase l at V1 + l - 1 (PV units)
IFT = 30  # largest IFT between the ME and an excess phase present (oil-water without ME; 0 single ME), mN/m
C1P = 31  # water fraction of phase l at C1P + l - 1
CSEP = 34  # polymer effective salinity of the carrier phase (Eq. 2.3), meq/ml
SIGW = 35  # IFT between the polymer carrier and the oleic phase (capillary pressure), mN/m
# rel-perm inputs and results of phase l at ROW + l - 1 (passes of ``cell_properties``)
KR = 36  # end point k_rl^0 (Eq. 2.13), then k_rl (Eq. 2.14)
DKR = 39  # dk_rl / dS_l
NEXP = 42  # Corey exponent n_l (Eq. 2.13)
SBAR = 45  # normalized saturation (Eq. 1.7), 0 for an absent phase
WINDOW = 48  # 1 - S1r - S2r - S3r
DPCDS = 49  # |dPc/dS| of the carrier (wetting) phase saturation (Pa), 0 where Pc is off or capped
WAVE_R = 50  # the release phase's term of the wave-speed bound: its row sum of |df_k/dS_l| (PV units)
SPEED_X = 51  # the step's speed bound without the release phase's Jacobian column (``SPEED >= max(SPEED_X, WAVE_R)``)
REL = 52  # the release phase (0 aqueous, 1 oleic, 2 microemulsion): the present phase with the largest dlambda/dS
NPR = 53

# error codes returned by the kernel
OK = 0
ERR_COLLAPSE = 1
ERR_NONFINITE = 2
ERR_IMMOBILE = 3
ERR_STEPS = 4
ERR_WALL = 5

# time discretisations of the capillary flux (``run_kernel``'s ``capillary_mode``; names in ``run_arguments.CAPILLARY``)
CAP_EXPLICIT = 0  # forward Euler with the diffusion limit dx^2 / (2 D_cap) on every step
CAP_IMPLICIT = 1  # the linearly implicit step on every step, at the advective step (saturation-change control)
CAP_ADAPTIVE = 2  # explicit while its diffusion limit is affordable, the implicit step where it is not
CAP_BUDGETED = 3  # explicit until a share of the step budget is used, then the budget step (adaptive Pc, release)
