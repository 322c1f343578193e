"""Checkpoints are generic over State's fields: extra arrays, nested dataclasses (contact sets), None."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import h5py
import numpy as np
import pytest

import srdda
from srdda.io.integrity import write_text
from srdda.io.checkpoint import append_checkpoint, checkpoint_count, read_checkpoint, truncate_checkpoints
from srdda.io.results_store import ResultsStore, contacts_from_state, read_results
from srdda.ledger import ENERGY_NAMES
from srdda.state import State, initial_state
from results_models import two_block_model


@dataclass(frozen=True)
class FakeContacts:
    """Stands in for a contact set: per-contact arrays of varying length and a scalar."""

    key: np.ndarray
    edge: np.ndarray
    state: np.ndarray
    normal_force: np.ndarray
    energy: float


@dataclass(frozen=True)
class ExtendedState(State):
    contacts: FakeContacts | None = None
    multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0))


def _states(n: int) -> list[ExtendedState]:
    arrays = two_block_model().arrays()
    base = initial_state(arrays, srdda.RunSettings(dt=1e-3, n_steps=1).resolved_method())
    rng = np.random.default_rng(0)
    out = []
    for k in range(n):
        nc = [0, 3, None, 1, 2][k % 5]
        contacts = None if nc is None else FakeContacts(
            rng.integers(0, 4, nc), rng.integers(4, 9, nc), rng.integers(0, 3, nc).astype(np.int8),
            rng.normal(size=nc), float(k))
        fields_ = {name: getattr(base, name) + 0.1 * k for name in ("vertices", "points", "velocity", "stress")}
        out.append(ExtendedState(step=k, time=1e-3 * k, acceleration=base.acceleration, rotation=base.rotation,
                                 moments=arrays.moments(fields_["vertices"]), contacts=contacts,
                                 multipliers=np.arange(k % 3, dtype=float), **fields_))
    return out


def _equal(a: ExtendedState, b: ExtendedState) -> None:
    assert type(a) is type(b) and a.step == b.step and a.time == b.time
    for name in ("vertices", "points", "velocity", "acceleration", "stress", "rotation", "multipliers"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    np.testing.assert_array_equal(a.moments.centroid, b.moments.centroid)
    if a.contacts is None:
        assert b.contacts is None
        return
    assert b.contacts.energy == a.contacts.energy
    for name in ("key", "edge", "state", "normal_force"):
        got, want = getattr(b.contacts, name), getattr(a.contacts, name)
        assert got.dtype == want.dtype
        np.testing.assert_array_equal(got, want, err_msg=name)


def test_every_field_round_trips_and_truncation_realigns(tmp_path: Path) -> None:
    arrays = two_block_model().arrays()
    states = _states(7)
    with h5py.File(tmp_path / "c.h5", "w") as f:
        g = f.create_group("checkpoint")
        for s in states[:5]:
            append_checkpoint(g, s)
        assert checkpoint_count(g) == 5
        for i, s in enumerate(states[:5]):
            _equal(s, read_checkpoint(g, i, arrays.moments))
        truncate_checkpoints(g, 2)  # drop checkpoints 2-4 (one of them without contacts), then continue
        for s in states[5:]:
            append_checkpoint(g, s)
        assert checkpoint_count(g) == 4
        for i, s in enumerate([*states[:2], *states[5:]]):
            _equal(s, read_checkpoint(g, i, arrays.moments))


def test_a_checkpoint_cut_short_is_not_counted(tmp_path: Path) -> None:
    states = _states(3)
    with h5py.File(tmp_path / "c.h5", "w") as f:
        g = f.create_group("checkpoint")
        append_checkpoint(g, states[0])
        append_checkpoint(g, states[1])
        g["step"].resize(1, axis=0)  # as if killed before the second checkpoint's step was written
        assert checkpoint_count(g) == 1
        truncate_checkpoints(g, 1)
        append_checkpoint(g, states[2])
        _equal(states[2], read_checkpoint(g, 1, two_block_model().arrays().moments))


def test_what_terms_carry_round_trips_with_names_that_come_and_go(tmp_path: Path) -> None:
    # State.carried maps term names to dataclasses: a name may appear at a later checkpoint (contacts found
    # only once blocks touch) and leave again; every checkpoint reads back its own entries, also after
    # truncation drops the last ones
    base = _states(6)
    rng = np.random.default_rng(1)

    def fake(n):
        return FakeContacts(rng.integers(0, 4, n), rng.integers(4, 9, n), rng.integers(0, 3, n).astype(np.int8),
                            rng.normal(size=n), float(n))

    carried = [{}, {"a": fake(2)}, {"a": fake(0), "b": fake(3)}, {"b": fake(1)}, {}, {"c": fake(4), "a": fake(1)}]
    states = [State(**{f: getattr(s, f) for f in ("step", "time", "vertices", "points", "velocity", "acceleration",
                                                  "stress", "rotation", "moments")}, carried=c)
              for s, c in zip(base, carried)]
    arrays = two_block_model().arrays()
    with h5py.File(tmp_path / "c.h5", "w") as f:
        g = f.create_group("checkpoint")
        for s in states[:4]:
            append_checkpoint(g, s)
        truncate_checkpoints(g, 3)
        for s in states[4:]:
            append_checkpoint(g, s)
        for i, want in enumerate([*states[:3], *states[4:]]):
            got = read_checkpoint(g, i, arrays.moments)
            assert set(got.carried) == set(want.carried), i
            for name, value in want.carried.items():
                np.testing.assert_array_equal(got.carried[name].key, value.key)
                np.testing.assert_array_equal(got.carried[name].normal_force, value.normal_force)
                assert got.carried[name].energy == value.energy


def test_a_checkpoint_of_a_field_this_state_lacks_is_refused(tmp_path: Path) -> None:
    # a checkpoint written with contacts on the State itself (srdda 0.1.0) would resume without them: refused,
    # with a message naming the field, rather than a run that silently lost its contacts
    with h5py.File(tmp_path / "c.h5", "w") as f:
        g = f.create_group("checkpoint")
        append_checkpoint(g, _states(2)[1])
        write_text(g, "state_class", "srdda.state:State")
        with pytest.raises(ValueError, match="contacts"):
            read_checkpoint(g, 0, two_block_model().arrays().moments)


def test_contact_sets_on_the_state_are_recorded_by_default(tmp_path: Path) -> None:
    arrays = two_block_model().arrays()
    state = _states(2)[1]  # three contacts
    out = contacts_from_state(arrays, state)
    c = state.contacts
    # every per-contact array of the set, whatever it holds; not its scalars
    assert set(out) == {"key", "edge", "state", "normal_force"}
    for name in out:
        np.testing.assert_array_equal(out[name], getattr(c, name))
    # a run's contact set: where each contact is, its foot on the other block and its normal
    resting = srdda.Model(gravity=(0.0, -9.81))
    resting.add_material("rock", srdda.Material(density=2600.0, young=5e9, poisson=0.3))
    resting.add_block([[-2, -1], [2, -1], [2, 0], [-2, 0]], "rock", fixed=True)
    resting.add_block([[0, 0], [1, 0], [1.2, 0.8], [0.1, 1]], "rock")
    run = srdda.run(resting, srdda.RunSettings(dt=1e-3, n_steps=3))
    real = contacts_from_state(resting.arrays(), run.final_state)
    assert {"point", "point_b", "normal", "state", "normal_force", "gap", "shear", "direction"} <= set(real)
    np.testing.assert_allclose(np.linalg.norm(real["normal"], axis=1), 1.0, rtol=1e-15)
    across = real["point"] - real["point_b"]  # along the normal: x_b is the foot of x_a
    cross = across[:, 0] * real["normal"][:, 1] - across[:, 1] * real["normal"][:, 0]
    np.testing.assert_allclose(cross, 0.0, atol=1e-15)  # the coordinates are O(1) m
    plain = initial_state(arrays, srdda.RunSettings(dt=1e-3, n_steps=1).resolved_method())
    assert contacts_from_state(arrays, plain) is None  # a State without contact sets records none

    store = ResultsStore(tmp_path / "s.h5", srdda.RunSettings(dt=1e-3, n_steps=4), flush_every=2)
    for s in _states(5):
        store.record(arrays, s, 1, dict.fromkeys(ENERGY_NAMES, 0.0))
    store.finish("completed", s)
    stored = read_results(tmp_path / "s.h5")
    np.testing.assert_array_equal(stored.contacts["step"], [0, 1, 3, 4])  # step 2 has no contact set
    np.testing.assert_array_equal(np.diff(stored.contacts["offsets"]), [0, 3, 1, 2])
