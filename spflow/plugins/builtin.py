"""The built-in plugin: registers spflow's own stages, effects, surrogate kinds and commands through the public hooks."""

from __future__ import annotations

from spflow.core.hookspecs import hookimpl


#: Built-in stages by name and reference: ``spflow list`` and a run import only the stage modules they use.
STAGES = {
    "load_netcdf": "spflow.plugins.data:LoadNetCDF",
    "observations": "spflow.plugins.observations:Observations",
    "parameter_space": "spflow.plugins.design.parameter_space:ParameterSpace",
    "lhs_design": "spflow.plugins.design.latin_hypercube:LatinHypercubeDesign",
    "forward": "spflow.plugins.forward.stage:Forward",
    "quantiles": "spflow.plugins.statistics.quantiles:Quantiles",
    "sobol_screening": "spflow.plugins.screening.sobol_screening:SobolScreening",
    "morris_screening": "spflow.plugins.screening.morris_screening:MorrisScreening",
    "selected_space": "spflow.plugins.screening.selected_space:SelectedSpace",
    "pce": "spflow.plugins.surrogates.pce_stage:PCEStage",
    "adaptive_pce": "spflow.plugins.surrogates.adaptive_design:AdaptivePCE",
    "surrogate_validation": "spflow.plugins.surrogates.validation:SurrogateValidation",
    "pck": "spflow.plugins.surrogates.kriging_stage:PCKStage",
    "gp": "spflow.plugins.surrogates.kriging_stage:GPStage",
    "nsga2_calibration": "spflow.plugins.calibration.nsga2_stage:NSGA2Calibration",
    "pareto_design": "spflow.plugins.calibration.nsga2_pareto_design:ParetoDesign",
    "emcee_sampler": "spflow.plugins.calibration.emcee_sampler:EmceeSampler",
    "mh_sampler": "spflow.plugins.calibration.mh_sampler:MHSampler",
    "posterior_predictive": "spflow.plugins.calibration.posterior_predictive:PosteriorPredictive",
    "diagnose": "spflow.plugins.gap.stage:Diagnose",
    "fit_polymer_rheology": "spflow.plugins.lab.polymer_fit_stages:FitPolymerRheology",
    "fit_polymer_coreflood": "spflow.plugins.lab.polymer_fit_stages:FitPolymerCoreflood",
    "fit_adsorption": "spflow.plugins.lab.polymer_fit_stages:FitAdsorption",
    "fit_tracer": "spflow.plugins.lab.polymer_fit_stages:FitTracer",
    "fit_phase_behaviour": "spflow.plugins.lab.surfactant_fit_stages:FitPhaseBehaviour",
    "fit_ift": "spflow.plugins.lab.surfactant_fit_stages:FitIFT",
    "fit_me_viscosity": "spflow.plugins.lab.surfactant_fit_stages:FitMEViscosity",
    "fit_desaturation": "spflow.plugins.lab.surfactant_fit_stages:FitDesaturation",
    "priors": "spflow.plugins.lab.priors:Priors",
    "slug_design": "spflow.plugins.slug_design.stage:SlugDesign",
}


@hookimpl
def spflow_register_stages(register):
    for name, reference in STAGES.items():
        register(reference, name=name)


#: Built-in surrogate kinds, registered by reference: a kind's module (the Kriging ones import SciPy's linear
#: algebra) loads when a surrogate of that kind is first rebuilt, not when the registry is built.
SURROGATE_KINDS = {
    "pce": "spflow.plugins.surrogates.pce_model:PCE",
    "gp": "spflow.plugins.surrogates.gp_model:GP",
    "pck": "spflow.plugins.surrogates.pck_model:PCK",
}


@hookimpl
def spflow_register_surrogate_kinds(register):
    for kind, reference in SURROGATE_KINDS.items():
        register(reference, kind=kind)


@hookimpl
def spflow_register_commands(register):
    from spflow.export import command as export_command
    from spflow.plugins.gap import command as diagnose_command
    from spflow.study import command as study_command

    register(("diagnose",), diagnose_command.add_parser, diagnose_command.main)
    register(("export", "compare"), export_command.add_parser, export_command.main)
    register(("init", "check"), study_command.add_parser, study_command.main)


@hookimpl
def spflow_register_effects(register):
    from spflow.plugins.forward.effects import register_builtin_effects

    register_builtin_effects(register)
