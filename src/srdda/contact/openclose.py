"""The open-close rules: from a solved step, the state each contact should have had (2D and 3D).

States: OPEN (no spring), SLIDING (normal spring + Coulomb friction force
opposing the slip), LOCKED (normal and shear springs). Shi (1988), ch. 4:

* a contact is closed while its normal force N = -k_n·g_n stays above minus its
  tensile strength (T·l, only while the contact is bonded), else OPEN;
* a closed contact is LOCKED while the shear spring force |k_s·s| is at most
  the Mohr-Coulomb strength N·tan φ + c·l (c·l only while bonded), else
  SLIDING in the direction of s;
* a contact that closes is LOCKED first: its normal force, which sets the
  friction of a sliding contact, is known only after a solve with it closed;
* a SLIDING contact keeps its slip direction and locks only when its slip
  reverses (friction can stop a block, never push it back).

The shear is a vector of the contact's frame (one component in 2D, two in
3D) and the slip direction a unit vector of it (±1 in 2D). A contact whose
shear spring is *dragged* (a 3D vertex-face contact, docs/contacts.md,
"Sliding springs dragged at their strength") starts a step sliding with its
spring held at its strength along the slip direction: it locks again once the
spring holds (|k_s·s| within the strength), its reversal is measured by the
step's slip s − s_0 (not from the dragged reference), and the direction it
takes into the next step is that of the trial force ŝ·strength/k_s + slip (an
elastic predictor and plastic corrector, Simo & Hughes 1998, ch. 2).

Shi's tolerance f0·w0 (``tolerance``; f0 = 2e-7 in Shi's and ntdda's codes)
keeps the iteration short on packed models: a closed contact opens only once
its gap exceeds f0·w0 (plus T/k_n), a slip must reverse by more than f0·w0,
and a sliding contact's friction is re-iterated only while it is off by more
than the negligible force below (k_s·f0·w0 let a sliding block's acceleration
err by 1e-3: that force scales with the model, not the block). An open
contact still closes at any penetration, so no spring starts compressed
(docs/contacts.md, "Open-close convergence"). A contact still held closed in
the band when the iteration ends is committed OPEN
(:meth:`srdda.contact.pipeline.ContactStep.commit`): its spring's energy is dropped.
The band's pull is not free of work: where a contact's gap shrank in the step
(g₀ > g > 0), the pull k_n·g does the work k_n·g·(g₀ − g) on the blocks, which
the ledger books as less ``dissipated_contact`` (measured in docs/contacts.md,
"The band's pull"). ``tolerance`` = 0 gives the exact rules.

Two additions make impacts converge (docs/contacts.md):

* a contact that closed during this step's iterations (it was OPEN and the
  solve drove it into the edge) and then, LOCKED, pulls in tension, SLIDES
  instead of re-opening: the tension comes from the shear spring stopping a
  glancing vertex dead, the open <-> locked cycle never ends, and a vertex
  that penetrates when free must be pushed, not pulled;
* the friction of a sliding contact uses the normal force of the previous
  solve (Shi); the step is iterated until that force has settled to
  ``friction_tolerance`` (relative) as well (for at most a few solves in
  large systems, see :mod:`srdda.contact.pipeline`).

Negligible changes (``open_close_force_tolerance`` ε, :func:`negligible_force`):
a contact that closes with a normal force below ε·F, or a locked one whose
shear spring exceeds its strength by less, takes its new state without another
solve; F is the pair's force scale (docs/contacts.md, "Negligible state
changes").
"""
from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["OPEN", "SLIDING", "LOCKED", "next_states", "negligible_force", "negligible_changes", "never_held",
           "deepest_penetration", "magnitudes"]

OPEN, SLIDING, LOCKED = 0, 1, 2


def magnitudes(vectors: np.ndarray) -> np.ndarray:
    """|v| (n,) of vectors (n, k): the absolute value when k = 1 (exactly, as 2D has always had it)."""
    return np.abs(vectors[:, 0]) if vectors.shape[1] == 1 else np.linalg.norm(vectors, axis=1)


def next_states(state: np.ndarray, direction: np.ndarray, gap: np.ndarray, shear: np.ndarray, slip: np.ndarray,
                normal_stiffness: np.ndarray, shear_stiffness: np.ndarray, strength: np.ndarray,
                friction: np.ndarray, tension: np.ndarray, closed_this_step: np.ndarray,
                friction_normal: np.ndarray, dragged: np.ndarray, friction_tolerance: float = 1e-3,
                tolerance: float = 0.0, settled_force: np.ndarray | float = 0.0
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """New (state, slip direction, trial direction, changed, unsettled) for end-of-solve gaps and shears.

    ``shear`` (n, k): the shear springs' stretch from their references;
    ``slip`` (n, k): the step's tangential motion s − s_0; ``direction``
    (n, k): the slip direction of sliding contacts (zero: sliding without
    friction); ``strength``: the shear strength at this solve's compression
    (:class:`srdda.contact.law.JointResponse`), ``friction`` its slope in the
    compression, ``tension`` what a closed contact carries before it opens;
    ``dragged``: contacts whose sliding spring is dragged at its strength
    (module doc). The *trial direction* is the one a dragged contact that
    slides takes into the next step (its slip direction otherwise).

    ``unsettled``: sliding contacts whose friction used a normal force more
    than ``friction_tolerance`` (relative) away from the solved one, and whose
    friction force is off by more than ``settled_force`` (N, per contact: the
    negligible force of :func:`negligible_force`).

    ``closed_this_step`` marks contacts that were OPEN in an earlier solve of
    this step; ``friction_normal`` is the normal force the last solve used for
    the friction of sliding contacts.
    """
    n, k = shear.shape
    new_state = np.empty(n, dtype=np.int8)
    new_direction, trial = np.empty((n, k)), np.empty((n, k))
    changed, unsettled = np.empty(n, dtype=bool), np.empty(n, dtype=bool)
    _next_states(state, np.ascontiguousarray(direction, dtype=np.float64), gap, np.ascontiguousarray(shear),
                 np.ascontiguousarray(slip), normal_stiffness, shear_stiffness, strength, friction, tension,
                 closed_this_step, friction_normal, dragged, float(friction_tolerance), float(tolerance),
                 np.broadcast_to(np.asarray(settled_force, dtype=np.float64), (n,)), new_state, new_direction, trial,
                 changed, unsettled)
    return new_state, new_direction, trial, changed, unsettled


@njit(cache=True)
def _size(v: np.ndarray) -> float:
    """|v| of one shear vector: the absolute value of a single component (exactly)."""
    if v.shape[0] == 1:
        return abs(v[0])
    acc = 0.0
    for j in range(v.shape[0]):
        acc += v[j] * v[j]
    return np.sqrt(acc)


@njit(cache=True)
def _unit_into(v: np.ndarray, out: np.ndarray) -> None:
    """out = v/|v| (zero for a zero vector); ±1 for a single component."""
    size = _size(v)
    for j in range(v.shape[0]):
        out[j] = v[j] / size if size > 0.0 else 0.0


@njit(cache=True)
def _next_states(state: np.ndarray, direction: np.ndarray, gap: np.ndarray, shear: np.ndarray, slip: np.ndarray,
                 kn: np.ndarray, ks: np.ndarray, strength: np.ndarray, friction: np.ndarray, tension: np.ndarray,
                 closed_this_step: np.ndarray, friction_normal: np.ndarray, dragged: np.ndarray,
                 friction_tolerance: float, tolerance: float, settled_force: np.ndarray, new_state: np.ndarray,
                 new_direction: np.ndarray, trial: np.ndarray, changed: np.ndarray, unsettled: np.ndarray) -> None:
    """:func:`next_states` contact by contact, into the five outputs (the gap and shear are finite: a solve
    that is not has already failed)."""
    n, k = shear.shape
    probe = np.empty(k)
    for c in range(n):
        normal = -kn[c] * gap[c]
        # a closed contact opens once its gap exceeds T/k_n + tolerance (Shi's f0·w0), an open one
        # closes at any penetration (so no spring starts compressed)
        closed = normal >= -tension[c] - (kn[c] * tolerance if state[c] != OPEN else 0.0)
        compression = normal if normal > 0.0 else 0.0
        # a sliding contact locks only when its slip reverses by more than the tolerance (Shi), and keeps
        # its slip direction while it slides; a dragged spring measures the reversal by the step's slip
        along = 0.0
        for j in range(k):
            along += direction[c, j] * (slip[c, j] if dragged[c] else shear[c, j])
        reversed_slip = state[c] == SLIDING and along < -tolerance and strength[c] > 0.0
        holds = ks[c] * _size(shear[c]) <= strength[c] and (state[c] != SLIDING or dragged[c])
        if not closed:
            after = OPEN
        elif holds or reversed_slip or state[c] == OPEN:  # a contact that closes locks first
            after = LOCKED
        else:
            after = SLIDING
        if state[c] == LOCKED and not closed and closed_this_step[c]:  # glancing
            after = SLIDING
        new_state[c] = after
        moved = False
        if after == SLIDING and state[c] == SLIDING:
            new_direction[c] = direction[c]
            if dragged[c]:  # the trial force of a spring held at its strength
                limit = strength[c] / ks[c]
                for j in range(k):
                    probe[j] = direction[c, j] * limit + slip[c, j]
                _unit_into(probe, trial[c])
            else:
                trial[c] = direction[c]
        elif after == SLIDING:  # it starts to slide along the load its spring carried
            _unit_into(shear[c], new_direction[c])
            trial[c] = new_direction[c]
        else:
            new_direction[c] = 0.0
            trial[c] = 0.0
        if after == SLIDING:
            for j in range(k):
                moved = moved or new_direction[c, j] != direction[c, j]
        acts = friction[c] > 0.0
        changed[c] = after != state[c] or (moved and acts)
        off = abs(compression - friction_normal[c])
        unsettled[c] = after == SLIDING and state[c] == SLIDING and acts and (
            off > friction_tolerance * compression) and off * friction[c] > settled_force[c]


def negligible_force(block_mass: np.ndarray, gravity: np.ndarray, block_a: np.ndarray, block_b: np.ndarray,
                     normal: np.ndarray, tolerance: float) -> np.ndarray:
    """Per contact, the force below which a state change needs no solve: ``tolerance`` × the pair's scale.

    A block's force scale is the larger of its weight and its largest contact
    normal force ``normal`` (N, compression positive); a pair takes the
    smaller of its two blocks' (a light block beside heavy ones keeps a fine
    tolerance; a fixed base never sets it).
    """
    out = np.empty(len(normal))
    _pair_force_scale(block_mass * float(np.linalg.norm(gravity)), block_a, block_b, normal, out)
    return tolerance * out


@njit(cache=True)
def _pair_force_scale(scale: np.ndarray, block_a: np.ndarray, block_b: np.ndarray, normal: np.ndarray,
                      out: np.ndarray) -> None:
    """out[c]: the smaller of contact c's two blocks' force scales, each the larger of ``scale`` (the block's
    weight, overwritten) and its contacts' ``normal`` (np.maximum's rule: a NaN wins)."""
    for c in range(len(normal)):
        value = normal[c]
        for block in (block_a[c], block_b[c]):
            if value > scale[block] or value != value:
                scale[block] = value
    for c in range(len(normal)):
        a, b = scale[block_a[c]], scale[block_b[c]]
        out[c] = a if a <= b or a != a else b


def negligible_changes(state: np.ndarray, new_state: np.ndarray, normal: np.ndarray, shear_force: np.ndarray,
                       strength: np.ndarray, limit: np.ndarray) -> np.ndarray:
    """Closings with a normal force, and slips with a spring force beyond the strength, at most ``limit``."""
    closing = (state == OPEN) & (new_state != OPEN) & (normal <= limit)
    slipping = (state == LOCKED) & (new_state == SLIDING) & (shear_force - strength <= limit)
    return closing | slipping


def never_held(state: np.ndarray, new_state: np.ndarray, gap: np.ndarray, band: float, flips: np.ndarray,
               freeze_after: int) -> np.ndarray:
    """State changes the iteration's freezing never holds back: they keep forces bounded and store no energy.

    A locked contact that slips (a locked spring past its strength would load
    further step after step), an open one that penetrates by more than ``band``
    and a closed one open by more than ``band`` (not a rounding at a zero gap).
    Opening is held too once a contact has changed state 2 × ``freeze_after``
    times in the step: it cycles open -> locked -> sliding -> open, each change
    safe by itself; held closed in tension for the step, its spring takes
    energy out while the blocks separate (the contact is committed open, its
    energy dropped); where they approached in the step it does the work of
    the band's pull (module doc).
    """
    cycling = flips >= 2 * freeze_after
    return (((state == LOCKED) & (new_state == SLIDING)) | ((state == OPEN) & (gap < -band))
            | ((state != OPEN) & (new_state == OPEN) & (gap > band) & ~cycling))


def deepest_penetration(state: np.ndarray, gap: np.ndarray) -> float:
    """The largest penetration -g (m) of the closed contacts, 0 when none penetrates."""
    pen = -gap[state != OPEN]
    return float(max(pen.max(), 0.0)) if len(pen) else 0.0
