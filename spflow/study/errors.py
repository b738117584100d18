"""The error of an invalid study (:class:`StudyError`)."""

from __future__ import annotations

from spflow.core.errors import ParameterError

__all__ = ["StudyError"]


class StudyError(ParameterError):
    """A study file, or a data file it names, is invalid; the message names the file, the field and the allowed
    values. A ``ValueError`` (via :class:`~spflow.core.errors.ParameterError`), so ``spflow`` commands exit 2."""
