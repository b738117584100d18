"""The new user's data for the study tests: two corefloods of a core unlike Berea's (0.30 m x 1.5 in, porosity 0.19,
0.5 ml/min, Swi 0.28, 350 mD) made by the twin generator with a documented measurement chain (``CHAIN``: 0.5 ml dead
volume, no transducer offset or drift, 0.1 PV tubes, dp every 0.05 PV, the NoiseModel's relative noise levels) -- a
polymer-only flood typed as a lab CSV (dp in psi, core data in the header, no permeability, no measurement chain)
and an SP flood as netCDF -- and the edit the user makes to the study ``spflow init`` writes for them."""

from pathlib import Path

from spflow.synthetic import NoiseModel, make_coreflood

PSI = 6894.757293168361
INCH = 0.0254
CORE = {"LENGTH": 0.30, "DIAMETER": 1.5 * INCH, "PORO": 0.19, "PERM": 350.0, "QINJ": 0.5, "SWI": 0.28,
        "S1RWC": 0.28}
POLYMER = [{"name": "WF", "pv": 1.2, "salinity_ppm": 9400.0},
           {"name": "P", "pv": 0.8, "salinity_ppm": 9400.0, "polymer_ppm": 1500.0},
           {"name": "CW", "pv": 1.0, "salinity_ppm": 9400.0}]
SP = [{"name": "WF", "pv": 1.0, "salinity_ppm": 9400.0},
      {"name": "SP", "pv": 0.5, "salinity_ppm": 9400.0, "surfactant_ppm": 6780.0, "polymer_ppm": 2000.0},
      {"name": "P", "pv": 0.8, "salinity_ppm": 9400.0, "polymer_ppm": 2000.0},
      {"name": "CW", "pv": 0.7, "salinity_ppm": 9400.0}]
CHAIN = NoiseModel(dead_volume_ml=0.5, pressure_offset_pa=0.0, pressure_drift_pa_per_pv=0.0, tube_pv=0.1,
                   pressure_interval_pv=0.05)


def lab_csv(ds, path):
    """The twin as a lab would type it: dp in psi, tubes as oil cut and recovery, core data in the header."""
    rows = {}
    for pv, dp in zip(ds["pv"].values, ds["dp"].values):
        rows.setdefault(round(float(pv), 9), {})["dp"] = float(dp) / PSI
    for i, end in enumerate(ds["pv_tube_end"].values):
        rows.setdefault(round(float(end), 9), {}).update(oil_cut=float(ds["oil_cut"].values[i]),
                                                        recovery=float(ds["recovery"].values[i]))
    lines = ["# experiment: poly7", "# core_length_m: 0.30", "# core_diameter: 1.5 in", "# porosity: 0.19",
             "# swi: 0.28", "# rate_ml_min: 0.5", "# units: dp=psi", "pv,dp,oil_cut,recovery"]
    for pv in sorted(rows):
        cells = [rows[pv].get(c) for c in ("dp", "oil_cut", "recovery")]
        lines.append(",".join([repr(pv)] + ["" if v is None else repr(v) for v in cells]))
    path.write_text("\n".join(lines) + "\n")



def write_user_data(directory: Path, cells: int = 20) -> None:
    """``poly7.csv`` (polymer flood, lab CSV) and ``sp8.nc`` (SP flood, netCDF) in ``directory``."""
    poly = make_coreflood({"name": "poly", "slugs": POLYMER}, CORE, noise=CHAIN, seed=7, cells=cells, pv_step=0.01)
    lab_csv(poly, directory / "poly7.csv")
    sp = make_coreflood({"name": "sp", "slugs": SP}, CORE, noise=CHAIN, seed=8, cells=cells, pv_step=0.01,
                        experiment="sp8")
    sp.to_netcdf(directory / "sp8.nc")


def edited(text: str) -> str:
    """The study text ``spflow init`` wrote, after the user's edit: the measured permeability, the polymer flood's
    slugs and the rig's measurement chain."""
    text = text.replace('permeability = "700 mD"  # DEFAULT', 'permeability = "0.35 D"  # measured')
    start = text.index("schedule = [{ name = \"WF\", pv = 3")
    end = text.index("\n", start)
    text = text[:start] + ('schedule = [{ pv = 1.2, salinity_ppm = 9400 }, { pv = 0.8, salinity_ppm = 9400, '
                           'polymer_ppm = 1500 }, { pv = 1.0, salinity_ppm = 9400 }]') + text[end:]
    first = text.index("[experiment.measurement]")
    text = text[:first] + ("[experiment.measurement]\ndead_volume_ml = 0.5\ntube_pv = 0.1\npressure_interval_pv = "
                           "0.05\npressure_offset_pa = 0.0\npressure_drift_pa_per_pv = 0.0\n")\
        + text[text.index("\n", first) + 1:]
    return text
