"""Which observations form the vectors a diagnosis compares, in which order, with which error model.

A :class:`Block` is one (variable, experiment) series at the grid points where it was measured, labelled with the
slug being injected at each point (``<qoi>:<slug>:<pv>`` naming). A :class:`Layout` concatenates
blocks into one vector and whitens residual vectors block by block (:mod:`spflow.plugins.gap.error_model`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from spflow.core.errors import ParameterError

from .error_model import BlockErrorModel, block_error_model, uninformative
from .observed import Experiment

__all__ = ["Block", "Layout", "make_layout"]


@dataclass(frozen=True)
class Block:
    """One measured series: grid positions ``index`` of its finite observations, their PV, values and slugs."""

    variable: str
    experiment: str
    index: np.ndarray
    pv: np.ndarray
    observed: np.ndarray
    slug: np.ndarray
    noise: BlockErrorModel


@dataclass(frozen=True)
class Layout:
    """An ordered set of blocks; vectors are the blocks' points concatenated in this order."""

    blocks: tuple[Block, ...]

    @property
    def experiments(self) -> list[str]:
        return sorted({b.experiment for b in self.blocks})

    @property
    def variables(self) -> list[str]:
        return sorted({b.variable for b in self.blocks})

    @property
    def size(self) -> int:
        return int(sum(b.index.size for b in self.blocks))

    def slices(self) -> list[slice]:
        edges = np.concatenate(([0], np.cumsum([b.index.size for b in self.blocks])))
        return [slice(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:])]

    def observed(self) -> np.ndarray:
        return np.concatenate([b.observed for b in self.blocks])

    def vector(self, predictions: Mapping[str, Mapping[str, np.ndarray]]) -> np.ndarray:
        """Predictions (experiment -> variable -> series on the grid) at this layout's points."""
        return np.concatenate([np.asarray(predictions[b.experiment][b.variable])[b.index] for b in self.blocks])

    def whiten(self, e: np.ndarray) -> np.ndarray:
        """Whitened residuals of ``e`` (points on axis 0), block by block."""
        return np.concatenate([b.noise.whiten(e[s]) for b, s in zip(self.blocks, self.slices())])

    def log_determinant(self) -> float:
        """``log det Sigma`` of the whole vector's error covariance (blocks are independent)."""
        return float(sum(b.noise.log_determinant() for b in self.blocks))

    def marginal_std(self) -> np.ndarray:
        return np.concatenate([b.noise.marginal_std() for b in self.blocks])

    def subset(self, keep: np.ndarray) -> Layout:
        """The layout of the points where ``keep`` (over the concatenated vector) is true; each block's AR(1)
        recursion then runs over its kept points as if they were consecutive."""
        blocks = []
        for b, s in zip(self.blocks, self.slices()):
            k = np.asarray(keep[s], bool)
            if k.any():
                blocks.append(Block(b.variable, b.experiment, b.index[k], b.pv[k], b.observed[k], b.slug[k],
                                    BlockErrorModel(b.noise.scale[k], b.noise.phi)))
        return Layout(tuple(blocks))

    def select(self, experiments: Sequence[str] | None = None, variables: Sequence[str] | None = None) -> Layout:
        """The sub-layout of the given experiments and/or variables (order kept)."""
        return Layout(tuple(b for b in self.blocks if (experiments is None or b.experiment in experiments)
                            and (variables is None or b.variable in variables)))


def make_layout(experiments: Sequence[Experiment], variables: Sequence[str] | None = None, *,
                report_only: Sequence[str] = (), dropped: list[str] | None = None) -> Layout:
    """Blocks of every measured variable (or only ``variables``) of every experiment, experiments first.

    An assay of a species the experiment never injects that reads zero throughout is left out (it carries no
    information, :func:`~spflow.plugins.gap.error_model.uninformative`), with a note appended to ``dropped``. Any other block whose error model is
    degenerate (no noise scale can weight its misfit) raises ``ParameterError`` naming the variable, experiment and
    file, unless its variable is in ``report_only`` (shown in reports, not in any likelihood): then it is left out
    and a note saying so is appended to ``dropped``."""
    blocks = []
    for exp in experiments:
        for variable, series in exp.observed.items():
            if variables is not None and variable not in variables:
                continue
            index = np.flatnonzero(np.isfinite(series))
            if uninformative(variable, exp, series[index]):
                if dropped is not None:
                    dropped.append(f"variable {variable!r} of experiment {exp.name!r} ({exp.source}) left out: it "
                                   "reads zero throughout and the experiment never injects that species (no "
                                   "information)")
                continue
            pv = exp.pv[index]
            try:
                noise = block_error_model(variable, exp, series[index])
            except ParameterError as exc:
                where = f"variable {variable!r} of experiment {exp.name!r} ({exp.source})"
                if variable not in report_only:
                    raise ParameterError(f"{where}: {exc}") from None
                if dropped is not None:
                    dropped.append(f"{where} left out of the report (not in the likelihood): {exc}")
                continue
            blocks.append(Block(variable, exp.name, index, pv, series[index], exp.slug_index(pv), noise))
    return Layout(tuple(blocks))
