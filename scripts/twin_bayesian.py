"""Clean synthetic-twin acceptance of the chapter-4 Bayesian history match (issue 7).

A "clean twin" has its truth inside the prior box (the pipeline's space: the bundled study's Table 3.2 ranges, or
Table 4.1 under the thesis profile; the truth lies inside both), no withheld
mechanism (the model's own default effects) and measurement noise only (``NoiseModel`` with random transducer,
oil-reading and assay errors but zero offset, drift and dead volume). The script writes BCF1-3 twins to netCDF
files, runs the ``bayesian_calibration`` pipeline on them (PCE on BCF1, MCMC on BCF1's dp and oil cut, simulator on
posterior draws for BCF1-3) and prints

* the coverage of the held-out BCF2/BCF3 observations (dp and oil cut pooled) by the 90 % posterior predictive band
  (acceptance: 85-95 %);
* for each parameter whether the truth lies in the 95 % equal-tailed marginal credible interval (acceptance: >= 8
  of 9);
* the Geweke z of every parameter (acceptance: all |z| < 2), with R-hat and bulk ESS.

    .venv/bin/python scripts/twin_bayesian.py [--sampler emcee_sampler] [--noise-seed 8] [--samples 300 ...] [--out DIR]

The default sampler is the thesis's Metropolis-Hastings (``mh_sampler``): within the thesis budget its chains are
16 000 draws long, which Geweke's segment test needs; emcee's walkers are 888 draws long at the same budget (numbers
for both in ``docs/calibration.md``). Exit status 0 when all three criteria hold, 1 otherwise. :func:`twin_check`
returns the numbers.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path


import spflow
from spflow.pipelines import bayesian_calibration
from spflow.core.report_table import text_lines
from spflow.core.stage import StageContext
from spflow.plugins.calibration.diagnostics import summary
from spflow.plugins.design.parameter_map import ParameterMap
from spflow.plugins.design.parameter_space import ParameterSpace
from spflow.synthetic import NoiseModel, write_twins

#: The twin's truth per design column: inside Table 4.1 (and so Table 3.2), away from its bounds and from the model
#: defaults. The high / low trapping-number Corey exponent is the bundled study's ``n_high`` / ``n_low`` (every
#: phase's exponent, profile ``study``) or the thesis table's ``E2C`` / ``E2WC`` (the oleic one, profile ``thesis``).
TRUTH = {"ALPHAV2": 2.7, "HBNC70": 0.031, "HBNC71": 0.0175, "AD31": 0.42, "GAMHF": 63.0, "CRK": 0.074,
         "n_high": 1.75, "n_low": 2.25, "E2C": 1.75, "E2WC": 2.25, "ALPHAL1": 0.0108}

#: Measurement noise only: random errors as in the default lab model, no systematic offset, drift or dead volume.
CLEAN_NOISE = NoiseModel.random_only()


def twin_check(cache: Path, outdir: Path | None = None, jobs: int = 2, noise_seed: int = 7, **settings) -> dict:
    """Run the Bayesian pipeline on clean twins and return the acceptance numbers (module docstring)."""
    data_dir = Path(outdir or tempfile.mkdtemp(prefix="twin_bayesian_"))
    data_dir.mkdir(parents=True, exist_ok=True)
    columns = ParameterMap.of(ParameterSpace(**bayesian_calibration.pipeline(**settings).nodes["space"].params)
                              .run(StageContext("space", verbose=False)))
    truth_params = columns.forward_params([TRUTH[label] for label in columns.labels])
    observed = write_twins(data_dir, truth_params, noise=CLEAN_NOISE, seed=noise_seed,
                           cells=settings.get("cells", 100))
    start = time.perf_counter()
    result = spflow.run(bayesian_calibration.pipeline(observed=observed, **settings), cache=cache, jobs=jobs)
    seconds = time.perf_counter() - start
    posterior, bands = result["posterior"], result["predictive"]
    table = summary(posterior)
    inside = {str(n): bool(table["q025"].sel(param=n) <= TRUTH[str(n)] <= table["q975"].sel(param=n))
              for n in table["param"].values}
    lines = text_lines(bayesian_calibration.report(result, data_dir, truth=TRUTH)) if outdir else []
    return {"coverage_heldout": bayesian_calibration.held_out_coverage(bands), "truth_inside": inside,
            "geweke_z": {str(n): float(table["geweke_z"].sel(param=n)) for n in table["param"].values},
            "rhat": {str(n): float(table["rhat"].sel(param=n)) for n in table["param"].values},
            "ess_bulk": {str(n): float(table["ess_bulk"].sel(param=n)) for n in table["param"].values},
            "coverage": {f"{v}/{e}": float(bands[f"coverage_{v}"].sel(experiment=e))
                         for v in ("dp", "oil_cut") for e in bands["experiment"].values},
            "seconds": seconds, "report": lines}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=int, default=300, help="LHS training runs of the PCE")
    parser.add_argument("--sampler", default="mh_sampler", choices=["emcee_sampler", "mh_sampler"],
                        help="default: the thesis's Metropolis-Hastings, whose long chains App. E's Geweke test is for")
    parser.add_argument("--mcmc-samples", type=int, default=100_000)
    parser.add_argument("--burn", type=int, default=20_000)
    parser.add_argument("--draws", type=int, default=200)
    parser.add_argument("--noise-seed", type=int, default=7)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--cache", default=".spflow")
    parser.add_argument("--out", default="out/twin_bayesian")
    args = parser.parse_args(argv)
    numbers = twin_check(Path(args.cache), Path(args.out), jobs=args.jobs, noise_seed=args.noise_seed,
                         samples=args.samples, sampler=args.sampler, mcmc_samples=args.mcmc_samples, burn=args.burn,
                         draws=args.draws)
    print("\n".join(numbers["report"]))
    cover = numbers["coverage_heldout"]
    inside = sum(numbers["truth_inside"].values())
    worst = max(abs(z) for z in numbers["geweke_z"].values())
    print(f"\nclean twin ({args.sampler}, noise seed {args.noise_seed}, {numbers['seconds']:.0f} s):")
    print("  coverage per QoI/experiment: " + ", ".join(f"{k} {100 * v:.0f}%" for k, v in numbers["coverage"].items()))
    checks = [(0.85 <= cover <= 0.95, f"90% predictive band covers {100 * cover:.1f}% of held-out BCF2/BCF3 "
                                      "observations (accept 85-95%)"),
              (inside >= 8, f"truth inside the 95% credible interval for {inside} of 9 parameters (accept >= 8): "
                            + ", ".join(n for n, ok in numbers["truth_inside"].items() if not ok) + " outside"
               if inside < 9 else f"truth inside the 95% credible interval for {inside} of 9 parameters"),
              (worst < 2.0, f"max |Geweke z| = {worst:.2f} (accept < 2): "
                            + ", ".join(f"{n} {z:+.2f}" for n, z in numbers["geweke_z"].items()))]
    for ok, text in checks:
        print(f"  {'PASS' if ok else 'FAIL'}  {text}")
    return 0 if all(ok for ok, _ in checks) else 1


if __name__ == "__main__":
    sys.exit(main())
