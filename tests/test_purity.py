"""``run`` is a pure function of (model, settings): same inputs, same outputs, inputs untouched."""
import numpy as np

import srdda


def _model():
    m = srdda.Model(gravity=(0.0, -9.81))
    m.add_material("rock", srdda.Material(2500.0, 1e9, 0.25))
    m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "rock", angular_velocity=0.5)
    m.add_block([[1, 0], [2, 0], [2, 1], [1, 1]], "rock")
    m.add_point_spring([1, 0.5], [1, 0.5], 1e7)
    m.add_fixed_point([0, 0], stiffness=1e8)
    return m


def test_two_runs_are_identical_and_leave_the_model_alone():
    arrays = _model().arrays()
    records = {"": arrays, "attached.": arrays.attached}  # the model's arrays and its attached points'
    before = {(r, k): v.copy() for r, record in records.items() for k, v in record.__dict__.items()
              if isinstance(v, np.ndarray)}
    s = srdda.RunSettings(dt=1e-3, n_steps=50, method="srdda")
    r1, r2 = srdda.run(arrays, s), srdda.run(arrays, s)
    assert np.array_equal(r1.array("centroid"), r2.array("centroid"))
    assert np.array_equal(r1.array("velocity"), r2.array("velocity"))
    for (r, k), v in before.items():
        assert np.array_equal(getattr(records[r], k), v), r + k


def test_continuing_from_a_state_equals_one_long_run():
    arrays = _model().arrays()
    s = srdda.RunSettings(dt=1e-3, n_steps=40, method="srdda")
    whole = srdda.run(arrays, s)
    half = srdda.run(arrays, srdda.RunSettings(dt=1e-3, n_steps=20, method="srdda"))
    rest = srdda.run(arrays, srdda.RunSettings(dt=1e-3, n_steps=20, method="srdda"), state=half.final_state)
    assert rest.step[-1] == 40
    assert np.array_equal(rest.array("centroid")[-1], whole.array("centroid")[-1])
