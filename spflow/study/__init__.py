"""Studies: a user's corefloods, their roles, cores, schedules, fluids and measurement chains, the parameter space
and the base model, declared in one TOML file and validated before any simulation. See
``docs/your_own_data.md``.

One concept per module: ``schema`` (allowed keys, roles, defaultable fields), ``defaults`` (the record of a
default taken), ``experiment`` (one coreflood), ``study`` (the whole), ``study_file`` (reading and validating a
file), ``bundled`` (the shipped BCF1-3 study), ``template`` (``spflow init``), ``proposed_experiment`` (a gap
diagnosis's proposed next coreflood as a predict-only experiment), ``command`` (``spflow init`` / ``spflow check``),
``pipeline_inputs`` (what the packaged pipelines take from a study: training and held-out experiments as stage
parameters).
"""

from .bundled import bundled_study, bundled_study_path
from .defaults import DefaultTaken
from .errors import StudyError
from .experiment import Experiment
from .schema import ROLES, VERSION
from .study import Study
from .study_file import load_study

__all__ = ["DefaultTaken", "Experiment", "ROLES", "Study", "StudyError", "VERSION", "bundled_study",
           "bundled_study_path", "load_study"]
