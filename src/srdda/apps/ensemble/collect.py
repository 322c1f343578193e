"""What one ensemble run measures: collector crossings, runout, peak energy, the stop rule.

:class:`RockfallRecorder` is a :class:`srdda.results.Recorder`: at every
recorded step it takes the tracked block's centroid and generalized velocity,
and when the centroid passes a collector (signed distance ``(c - at)·n`` going
from negative to non-negative, the first time only) it interpolates linearly
between the two recorded steps to the crossing and stores the passing speed,
the translational and rotational kinetic energy and the bounce height there.

Definitions (docs/ensembles.md): translational energy ½·m·|v|², rotational
energy ½·ωᵀ·M_ωω·ω with M_ωω the rotation block of the block's mass matrix
(ρ·∫(x²+y²)dA in 2D); the bounce height is the height of the centroid above
the ground surface (the fixed blocks' boundary) straight below it, measured
along the model's vertical axis (y in 2D, z in 3D). In 2D every energy is per
metre of thickness (J/m), as the model's masses are.

:class:`SettleRule` is the run's ``stop`` predicate: the run ends when every
movable block has left the stop domain, or when each one is at rest or out of
it for ``rest_duration`` seconds without a break.
"""
from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from ...geometry.ground import Ground
from ...model import ModelArrays
from ...state import State, mass_density
from .spec import Collector, StopRule

__all__ = ["RockfallRecorder", "SettleRule", "COLLECTOR_FIELDS"]

# Per collector crossing, after the crossing point's coordinates and velocity components.
COLLECTOR_FIELDS = ("time", "speed", "angular_speed", "kinetic_translational", "kinetic_rotational", "kinetic",
                    "bounce_height")


class RockfallRecorder:
    """Collector crossings, peak kinetic energy and a thinned trajectory of one block over a run."""

    def __init__(self, arrays: ModelArrays, block: int, collectors: list[Collector],
                 trajectory_interval: float) -> None:
        self.block = block
        self.dim = arrays.block_type.dim
        self.names = [c.name for c in collectors]
        self.at = np.array([c.at for c in collectors], dtype=float).reshape(-1, self.dim)
        normal = np.array([c.normal for c in collectors], dtype=float).reshape(-1, self.dim)
        self.normal = normal / np.linalg.norm(normal, axis=1, keepdims=True) if len(normal) else normal
        self.ground = Ground(arrays)
        self.interval = trajectory_interval
        self.crossings: dict[str, dict[str, float]] = {}
        self.trajectory: list[list[float]] = []  # [t, x, y(, z)]
        self.start: np.ndarray | None = None
        self.end: np.ndarray | None = None
        self.max_kinetic = 0.0
        self.max_speed = 0.0
        self._previous: tuple[float, np.ndarray, np.ndarray] | None = None
        self._next_sample = 0.0

    def _kinetic(self, arrays: ModelArrays, state: State, velocity: np.ndarray) -> tuple[float, float]:
        """Translational and rotational kinetic energy of the tracked block at ``velocity`` (J, J/m in 2D)."""
        bt, b = arrays.block_type, self.block
        mom = state.moments
        mass_matrix = mass_density(arrays, mom)[b] * bt.mass_matrix(mom.volume[b:b + 1], mom.second[b:b + 1])[0]
        v, w = velocity[bt.translation], velocity[bt.rotation]
        return 0.5 * float(arrays.block_mass[b] * v @ v), 0.5 * float(w @ mass_matrix[bt.rotation, bt.rotation] @ w)

    def record(self, arrays: ModelArrays, state: State, solves: int, energy: Mapping[str, float]) -> None:
        bt = arrays.block_type
        centroid = state.moments.centroid[self.block].copy()
        velocity = state.velocity[self.block].copy()
        kt, kr = self._kinetic(arrays, state, velocity)
        self.max_kinetic = max(self.max_kinetic, kt + kr)
        self.max_speed = max(self.max_speed, float(np.linalg.norm(velocity[bt.translation])))
        if self.start is None:
            self.start = centroid
        self.end = centroid
        if state.time >= self._next_sample:
            self.trajectory.append([state.time, *centroid.tolist()])
            self._next_sample = state.time + self.interval
        if self._previous is not None and len(self.names):
            t0, c0, v0 = self._previous
            s0 = np.einsum("kd,kd->k", c0 - self.at, self.normal)
            s1 = np.einsum("kd,kd->k", centroid - self.at, self.normal)
            for k in np.flatnonzero((s0 < 0) & (s1 >= 0)):
                if self.names[k] not in self.crossings:
                    f = s0[k] / (s0[k] - s1[k])
                    self.crossings[self.names[k]] = self._crossing(
                        arrays, state, t0 + f * (state.time - t0), c0 + f * (centroid - c0),
                        v0 + f * (velocity - v0))
        self._previous = (state.time, centroid, velocity)

    def _crossing(self, arrays: ModelArrays, state: State, time: float, point: np.ndarray,
                  velocity: np.ndarray) -> dict[str, float]:
        bt = arrays.block_type
        kt, kr = self._kinetic(arrays, state, velocity)
        return {"time": float(time), **{a: float(x) for a, x in zip("xyz", point)},
               **{f"velocity_{a}": float(v) for a, v in zip("xyz", velocity[bt.translation])},
               "speed": float(np.linalg.norm(velocity[bt.translation])),
               "angular_speed": float(np.linalg.norm(velocity[bt.rotation])),
               "kinetic_translational": kt, "kinetic_rotational": kr, "kinetic": kt + kr,
               "bounce_height": float(point[-1] - self.ground.height_below(point))}

    def finish(self, status: str, state: State) -> None:
        if self.end is not None and (not self.trajectory or self.trajectory[-1][0] < state.time):
            self.trajectory.append([state.time, *self.end.tolist()])


class SettleRule:
    """The ``stop`` predicate of a run: all movable blocks out of the domain, or at rest (or out) long enough."""

    def __init__(self, arrays: ModelArrays, rule: StopRule) -> None:
        self.rule = rule
        self.block_type = arrays.block_type
        self.movable = np.flatnonzero(~arrays.block_fixed)
        centroid = arrays.moments(arrays.vertex_position).centroid
        reach = np.linalg.norm(arrays.vertex_position - centroid[arrays.vertex_block], axis=1)
        self.radius = np.maximum.reduceat(reach, arrays.block_ptr[:-1])[self.movable]  # farthest vertex (m)
        self.rest_since: float | None = None
        self.reason = "end_time"
        self.time_to_stop = math.nan

    def __call__(self, state: State) -> bool:
        bt = self.block_type
        v = state.velocity[self.movable]
        speed = np.linalg.norm(v[:, bt.translation], axis=1) + np.linalg.norm(v[:, bt.rotation], axis=1) * self.radius
        out = np.zeros(len(self.movable), dtype=bool)
        if self.rule.domain is not None:
            c = state.moments.centroid[self.movable]
            lo, hi = (np.asarray(x) for x in self.rule.domain)
            out = np.any((c < lo) | (c > hi), axis=1)
        if out.all():
            self.reason = "out_of_domain"
            return True
        if not np.all(out | (speed < self.rule.rest_speed)):
            self.rest_since = None
            return False
        if self.rest_since is None:
            self.rest_since = state.time
        # a millionth of a second against the rounding of summed steps
        if state.time - self.rest_since >= self.rule.rest_duration - 1e-6:
            self.reason, self.time_to_stop = "rest", self.rest_since
            return True
        return False
