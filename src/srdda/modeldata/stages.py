"""A stage of a staged analysis resolved against its model: what ``ModelArrays.stages`` holds.

:mod:`srdda.stages` (which re-exports it) resolves a :class:`~srdda.stages.Stage` into a :class:`StagePlan`
and applies its changes; the plan lives below the terms so that the model's arrays can hold it without
importing the stages (docs/architecture.md).
"""
from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

__all__ = ["StagePlan"]


@dataclass(frozen=True)
class StagePlan:
    """A stage resolved against its model: ``changes`` by :data:`srdda.stages.CHANGES` key, as JSON-able values
    (indices)."""

    name: str
    kind: str
    changes: Mapping[str, Any]
    run: Mapping[str, Any]
    tolerance: float
    max_steps: int
    reset_displacements: bool

    def to_json(self) -> dict[str, Any]:
        return dataclasses.asdict(self)

    @staticmethod
    def from_json(data: Mapping[str, Any]) -> StagePlan:
        return StagePlan(**data)
