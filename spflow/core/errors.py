"""Exception and warning types raised by spflow.

Every user-facing error names the thing that is wrong (stage, node, port, parameter, variable) and what was
expected, so that a failed run can be fixed without reading spflow's source.
"""

__all__ = [
    "SpflowError",
    "ParameterError",
    "SchemaError",
    "PipelineError",
    "StageError",
    "PluginError",
    "CacheError",
    "CacheIntegrityWarning",
    "CacheWarning",
    "PluginWarning",
    "DegreeCapWarning",
]


class SpflowError(Exception):
    """Base class of all spflow errors."""


class ParameterError(SpflowError, ValueError):
    """A stage parameter is unknown, of the wrong type or outside its allowed range."""


class SchemaError(SpflowError, ValueError):
    """A Dataset crossing a stage boundary does not match the declared schema."""


class PipelineError(SpflowError, ValueError):
    """The pipeline graph is malformed (unknown stage, unwired port, cycle, bad selection)."""


class PluginError(SpflowError):
    """A plugin contributed something invalid (duplicate name, wrong type)."""


class CacheError(SpflowError):
    """The result store cannot be used: not a spflow cache, or a write failed (full or read-only disk)."""


class StageError(SpflowError):
    """A stage raised while running; ``node`` and ``stage`` say where, ``__cause__`` holds the original error."""

    def __init__(self, node: str, stage: str, message: str):
        super().__init__(f"node {node!r} (stage {stage!r}) failed: {message}")
        self.node = node
        self.stage = stage


class CacheIntegrityWarning(UserWarning):
    """A cache entry failed its checksum; it is discarded and recomputed, never loaded."""


class CacheWarning(UserWarning):
    """A best-effort write to the cache (the per-pipeline manifest behind ``status``) failed; the run goes on."""


class PluginWarning(UserWarning):
    """A third-party plugin failed (at import, in a hook, or with an unknown hook) and is left out; spflow goes on."""


class DegreeCapWarning(UserWarning):
    """A degree-adaptive surrogate fit selected the largest degree it was allowed to try: the data may ask for more."""
