"""spflow — history matching, uncertainty quantification and design of surfactant-polymer corefloods.

A pipeline is a DAG of named stages (pluggy plugins) exchanging typed xarray Datasets; the executor caches every
result under a provenance key and runs independent work in parallel. See ``docs/`` for the user and plugin guides.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from spflow.core.lazy_exports import lazy_exports
from spflow.core.version import __version__

#: Public name -> the module defining it ("": a sub-module). ``import spflow`` imports none of them; each is imported
#: on first use, so ``import spflow`` and the CLI's cheap verbs do not pay for numba or the numerical libraries.
_EXPORTS = {
    **dict.fromkeys(("CacheError", "CacheIntegrityWarning", "CacheWarning", "ParameterError", "PipelineError",
                     "PluginError", "PluginWarning", "SchemaError", "SpflowError", "StageError"), "spflow.core.errors"),
    **dict.fromkeys(("NodeStatus", "RunResult", "run", "status"), "spflow.core.executor"),
    "canonical_hash": "spflow.core.hashing",
    "hookimpl": "spflow.core.hookspecs",
    "Param": "spflow.core.params",
    "Pipeline": "spflow.core.pipeline",
    **dict.fromkeys(("get_registry", "register_plugin", "reset_registry", "unregister_plugin"), "spflow.core.plugins"),
    **dict.fromkeys(("DaskRunner", "ProcessRunner", "Runner", "SequentialRunner", "ThreadRunner"),
                    "spflow.core.runners"),
    **dict.fromkeys(("DatasetSchema", "Variable"), "spflow.core.schema"),
    **dict.fromkeys(("Stage", "StageContext"), "spflow.core.stage"),
    "Effect": "spflow.plugins.forward.effects",
    "simulate": "spflow.plugins.forward.simulate",
    "load_coreflood": "spflow.io",
    **dict.fromkeys(("Study", "StudyError", "bundled_study", "load_study"), "spflow.study"),
    "synthetic": "",
}

__all__ = sorted([*_EXPORTS, "__version__"])
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)

if TYPE_CHECKING:  # what type checkers and IDEs see: the same names, imported eagerly
    from spflow import synthetic
    from spflow.core.errors import (CacheError, CacheIntegrityWarning, CacheWarning, ParameterError, PipelineError,
                                    PluginError, PluginWarning, SchemaError, SpflowError, StageError)
    from spflow.core.executor import NodeStatus, RunResult, run, status
    from spflow.core.hashing import canonical_hash
    from spflow.core.hookspecs import hookimpl
    from spflow.core.params import Param
    from spflow.core.pipeline import Pipeline
    from spflow.core.plugins import get_registry, register_plugin, reset_registry, unregister_plugin
    from spflow.core.runners import DaskRunner, ProcessRunner, Runner, SequentialRunner, ThreadRunner
    from spflow.core.schema import DatasetSchema, Variable
    from spflow.core.stage import Stage, StageContext
    from spflow.io import load_coreflood
    from spflow.plugins.forward.effects import Effect
    from spflow.plugins.forward.simulate import simulate
    from spflow.study import Study, StudyError, bundled_study, load_study
