"""Named conformance checks, their outcome and the one error that lists every broken contract.

A check is a :class:`Check` (a name, the contract it enforces and how to fix a violation) and a function that returns
on success, raises :class:`Broken` with what it found, or :class:`NotApplicable` with why it does not apply. A
:class:`Checklist` runs checks one after another, keeps going after a failure, and ends with a
:class:`ConformanceReport` of the checks that passed, or one :class:`ConformanceError` naming every check that failed
(scikit-learn's ``check_estimator`` pattern: each failure says which contract was broken and how to fix it).
"""

from __future__ import annotations

import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from spflow.core.errors import SpflowError

__all__ = ["Check", "Broken", "NotApplicable", "Failure", "ConformanceReport", "ConformanceError", "Checklist"]


@dataclass(frozen=True)
class Check:
    """One named check: ``contract`` is what must hold, ``fix`` what an author does when it does not."""

    name: str
    contract: str
    fix: str


class Broken(Exception):
    """Raised by a check function: the contract does not hold; the message says what was found."""


class NotApplicable(Exception):
    """Raised by a check function: the check does not apply to this subject; the message says why."""


@dataclass(frozen=True)
class Failure:
    """A failed check and what it found."""

    check: Check
    found: str

    def describe(self) -> str:
        return f"- {self.check.name}: {self.check.contract}\n    found: {self.found}\n    fix: {self.check.fix}"


@dataclass
class ConformanceReport:
    """What a ``check_*`` function verified: ``passed`` check names in order, ``skipped`` name -> reason."""

    subject: str
    passed: list[str] = field(default_factory=list)
    skipped: dict[str, str] = field(default_factory=dict)

    def __str__(self) -> str:
        lines = [f"{self.subject}: {len(self.passed)} checks passed: {', '.join(self.passed)}"]
        lines += [f"  skipped {name}: {why}" for name, why in self.skipped.items()]
        return "\n".join(lines)


class ConformanceError(SpflowError):
    """A plugin breaks one or more of spflow's contracts; ``failures`` lists them, ``report`` has what passed."""

    def __init__(self, report: ConformanceReport, failures: list[Failure]):
        self.report = report
        self.failures = list(failures)
        names = ", ".join(f.check.name for f in self.failures)
        lines = [f"{report.subject}: {len(self.failures)} check(s) failed ({names})"]
        lines += [f.describe() for f in self.failures]
        if report.passed:
            lines.append(f"passed: {', '.join(report.passed)}")
        lines += [f"skipped {name}: {why}" for name, why in report.skipped.items()]
        super().__init__("\n".join(lines))

    @property
    def failed(self) -> list[str]:
        """Names of the failed checks."""
        return [f.check.name for f in self.failures]


def _describe_exception(exc: BaseException) -> str:
    """``Type: message`` and the innermost frame, so a failure inside the subject's code can be found."""
    frames = traceback.extract_tb(exc.__traceback__)
    where = f" (at {frames[-1].filename}:{frames[-1].lineno})" if frames else ""
    return f"{type(exc).__name__}: {exc}{where}"


class Checklist:
    """Runs checks on one subject and collects their outcomes."""

    def __init__(self, subject: str):
        self.report = ConformanceReport(subject)
        self.failures: list[Failure] = []

    def run(self, check: Check, func: Callable[..., Any], *args: Any, needs: tuple[str, ...] = ()) -> bool:
        """Run ``func(*args)`` as ``check``; ``needs`` are checks that must have passed first (else it is skipped).
        Returns whether it passed."""
        missing = [n for n in needs if n not in self.report.passed]
        if missing:
            self.report.skipped[check.name] = f"needs {', '.join(missing)} to pass first"
            return False
        try:
            func(*args)
        except Broken as exc:
            self.failures.append(Failure(check, str(exc)))
            return False
        except NotApplicable as exc:
            self.report.skipped[check.name] = str(exc)
            return False
        except Exception as exc:  # the subject's own code raised inside the check: that is the finding
            self.failures.append(Failure(check, f"raised {_describe_exception(exc)}"))
            return False
        self.report.passed.append(check.name)
        return True

    def finish(self) -> ConformanceReport:
        """The report, or :class:`ConformanceError` listing every failure."""
        if self.failures:
            raise ConformanceError(self.report, self.failures)
        return self.report
