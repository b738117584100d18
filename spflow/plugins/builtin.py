"""The built-in plugin: registers spflow's own stages, effects, surrogate kinds and commands through the public hooks."""

from __future__ import annotations

from spflow.core.hookspecs import hookimpl


@hookimpl
def spflow_register_stages(register):
    from spflow.plugins.calibration.emcee_sampler import EmceeSampler
    from spflow.plugins.calibration.mh_sampler import MHSampler
    from spflow.plugins.calibration.nsga2_pareto_design import ParetoDesign
    from spflow.plugins.calibration.nsga2_stage import NSGA2Calibration
    from spflow.plugins.calibration.posterior_predictive import PosteriorPredictive
    from spflow.plugins.data import LoadNetCDF
    from spflow.plugins.design.latin_hypercube import LatinHypercubeDesign
    from spflow.plugins.design.parameter_space import ParameterSpace
    from spflow.plugins.forward.stage import Forward
    from spflow.plugins.gap.stage import Diagnose
    from spflow.plugins.lab.polymer_fit_stages import FitAdsorption, FitPolymerCoreflood, FitPolymerRheology, FitTracer
    from spflow.plugins.lab.surfactant_fit_stages import FitDesaturation, FitIFT, FitMEViscosity, FitPhaseBehaviour
    from spflow.plugins.lab.priors import Priors
    from spflow.plugins.observations import Observations
    from spflow.plugins.screening.morris_screening import MorrisScreening
    from spflow.plugins.slug_design.stage import SlugDesign
    from spflow.plugins.screening.selected_space import SelectedSpace
    from spflow.plugins.screening.sobol_screening import SobolScreening
    from spflow.plugins.statistics.quantiles import Quantiles
    from spflow.plugins.surrogates.adaptive_design import AdaptivePCE
    from spflow.plugins.surrogates.kriging_stage import GPStage, PCKStage
    from spflow.plugins.surrogates.pce_stage import PCEStage
    from spflow.plugins.surrogates.validation import SurrogateValidation

    for stage in (LoadNetCDF, Observations, ParameterSpace, LatinHypercubeDesign, Forward, Quantiles,
                  SobolScreening, MorrisScreening, SelectedSpace, PCEStage, AdaptivePCE, SurrogateValidation,
                  PCKStage, GPStage, NSGA2Calibration, ParetoDesign, EmceeSampler, MHSampler, PosteriorPredictive,
                  Diagnose, FitPolymerRheology, FitPolymerCoreflood, FitAdsorption, FitTracer, FitPhaseBehaviour,
                  FitIFT, FitMEViscosity, FitDesaturation, Priors, SlugDesign):
        register(stage)


@hookimpl
def spflow_register_surrogate_kinds(register):
    from spflow.plugins.surrogates.gp_model import GP
    from spflow.plugins.surrogates.pce_model import PCE
    from spflow.plugins.surrogates.pck_model import PCK

    for kind in (PCE, GP, PCK):
        register(kind)


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
