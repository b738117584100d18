"""spflow — history matching, uncertainty quantification and design of surfactant-polymer corefloods.

A pipeline is a DAG of named stages (pluggy plugins) exchanging typed xarray Datasets; the executor caches every
result under a provenance key and runs independent work in parallel. See ``docs/`` for the user and plugin guides.
"""

from __future__ import annotations

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
    "surrogates": "",
}

__all__ = sorted([*_EXPORTS, "__version__"])
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
