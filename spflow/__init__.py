"""spflow — history matching, uncertainty quantification and design of surfactant-polymer corefloods.

A pipeline is a DAG of named stages (pluggy plugins) exchanging typed xarray Datasets; the executor caches every
result under a provenance key and runs independent work in parallel. See ``docs/`` for the user and plugin guides.
"""

from __future__ import annotations

from spflow.core.errors import (
    CacheError,
    CacheIntegrityWarning,
    CacheWarning,
    ParameterError,
    PipelineError,
    PluginError,
    PluginWarning,
    SchemaError,
    SpflowError,
    StageError,
)
from spflow.core.executor import NodeStatus, RunResult, run, status
from spflow.core.hashing import canonical_hash
from spflow.core.hookspecs import hookimpl
from spflow.core.params import Param
from spflow.core.pipeline import Pipeline
from spflow.core.plugins import get_registry, register_plugin, reset_registry, unregister_plugin
from spflow.core.runners import DaskRunner, ProcessRunner, Runner, SequentialRunner, ThreadRunner
from spflow.core.schema import DatasetSchema, Variable
from spflow.core.stage import Stage, StageContext
from spflow.core.version import __version__
from spflow.plugins.forward.effects import Effect
from spflow.plugins.forward.simulate import simulate
from spflow.io import load_coreflood
from spflow.study import Study, StudyError, bundled_study, load_study
from spflow import synthetic

__all__ = [
    "CacheError",
    "CacheIntegrityWarning",
    "CacheWarning",
    "DaskRunner",
    "DatasetSchema",
    "Effect",
    "NodeStatus",
    "Param",
    "ParameterError",
    "Pipeline",
    "PipelineError",
    "PluginError",
    "PluginWarning",
    "ProcessRunner",
    "RunResult",
    "Runner",
    "SchemaError",
    "SequentialRunner",
    "SpflowError",
    "Stage",
    "StageContext",
    "StageError",
    "Study",
    "StudyError",
    "ThreadRunner",
    "Variable",
    "__version__",
    "bundled_study",
    "canonical_hash",
    "get_registry",
    "hookimpl",
    "load_coreflood",
    "load_study",
    "register_plugin",
    "reset_registry",
    "run",
    "simulate",
    "status",
    "synthetic",
    "unregister_plugin",
]
