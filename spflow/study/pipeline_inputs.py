"""What the packaged pipelines take from a study (:class:`StudyInputs`): which corefloods train the proxy and the
calibrations (role ``calibration``) and which are held out (role ``heldout``), each as the ``forward`` stage's
``{name, schedule, params}`` mapping (its own core, rate, fluids and schedule) and as the ``observations`` /
``diagnose`` stages' ``{name, data, sha256, attrs}`` mapping (its data file, digest and resolved metadata), plus the
study-wide fixed parameters, base-model effects and calibrated parameter space. Every such value enters the nodes'
parameters, so the provenance keys see an edited study or data file and rerun exactly what depends on it.

``resolve_study(None)`` is the bundled study (:func:`spflow.bundled_study`), so a pipeline built without a study runs
on BCF1-3 as before.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from .bundled import bundled_study
from .errors import StudyError
from .experiment import Experiment
from .study import Study
from .study_file import load_study

__all__ = ["StudyInputs", "resolve_study", "study_settings"]


def resolve_study(study) -> Study:
    """``study`` as a :class:`Study`: ``None`` -> the bundled study, a path -> :func:`load_study`, a Study as is."""
    if study is None:
        return bundled_study()
    if isinstance(study, Study):
        return study
    if isinstance(study, (str, Path)):
        return load_study(study)
    raise StudyError(f"study must be a path of a study file, a Study or None (the bundled study), got "
                     f"{type(study).__name__}")


def study_settings(study: Study) -> list[str]:
    """The lines a run prints at its start and records in its report: the study summary and every default taken."""
    return study.describe()


@dataclass(frozen=True)
class StudyInputs:
    """A study seen by a pipeline. ``training``: the experiments that train the proxy and the calibrations;
    ``heldout``: those that check them. Both default to the study's roles; a pipeline profile may override them
    (e.g. the thesis's BCF1-only training)."""

    study: Study
    training: tuple[Experiment, ...]
    heldout: tuple[Experiment, ...]

    @classmethod
    def of(cls, study=None, training: list[str] | None = None, heldout: list[str] | None = None) -> "StudyInputs":
        """The inputs of ``study`` (see :func:`resolve_study`); ``training`` / ``heldout`` name experiments to use
        instead of the roles. Raises :class:`StudyError` when the training set is empty, an experiment is in both or
        a training experiment has no data."""
        s = resolve_study(study)
        train = [s.experiment(n) for n in training] if training is not None else s.by_role("calibration")
        held = [s.experiment(n) for n in heldout] if heldout is not None else s.by_role("heldout")
        where = str(s.path) if s.path is not None else "(in memory)"
        if not train:
            raise StudyError(f"study {where}: no experiment has role 'calibration'; the pipelines train on them "
                             "(set role = \"calibration\" on at least one [[experiment]])")
        both = sorted({e.name for e in train} & {e.name for e in held})
        if both:
            raise StudyError(f"study {where}: experiment(s) {both} cannot both train and be held out")
        for e in train + held:
            if e.data is None:
                raise StudyError(f"study {where}: experiment {e.name!r} has no data file, so it cannot "
                                 f"{'train' if e in train else 'be held out'}; give it role 'predict'")
        return cls(s, tuple(train), tuple(held))

    @property
    def training_names(self) -> list[str]:
        return [e.name for e in self.training]

    @property
    def heldout_names(self) -> list[str]:
        return [e.name for e in self.heldout]

    @property
    def observed(self) -> tuple[Experiment, ...]:
        """Training then held-out experiments (those with data the pipelines compare with)."""
        return self.training + self.heldout

    @staticmethod
    def forward(experiments) -> list[dict]:
        """The ``forward`` stage's ``experiments`` for ``experiments``."""
        return [e.forward_experiment() for e in experiments]

    @staticmethod
    def observations(experiments) -> list[dict]:
        """The ``observations`` / ``diagnose`` stages' sources for ``experiments``."""
        return [e.observation_source() for e in experiments]

    def space(self) -> dict:
        """The ``parameter_space`` stage's parameters of the study's calibrated parameters (``[parameters.calibrated]``:
        one design column per label, a label setting one or several UTCHEM names, linear or log scale)."""
        space = self.study.parameter_space
        return {"names": list(space), "ranges": {label: dict(spec) for label, spec in space.items()}}

    def model(self) -> dict:
        """The study-wide forward-model settings every simulating node takes: ``fixed`` and ``effects``."""
        return {"fixed": dict(self.study.fixed), "effects": dict(self.study.effects)}

    def reference_flood(self) -> Experiment:
        """The slug design's reference flood: the first training experiment with a surfactant slug (else the first
        experiment of the study with one). Raises :class:`StudyError` when no experiment injects surfactant."""
        for e in (*self.training, *self.study.experiments):
            if any(s.surfactant_ppm > 0.0 for s in e.schedule.slugs):
                return e
        raise StudyError("no experiment of the study injects surfactant, so none can be the slug design's reference "
                         "flood (the design varies an SP slug)")
