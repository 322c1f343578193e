"""Step control: cut steps keep velocities exact; a run never loops forever."""
import numpy as np
import pytest

import srdda
from srdda.contact import ContactSet
from srdda.solvers import get_solver
from srdda.state import initial_state
from srdda.step import Stepper
from srdda.term import CUT_CAUSES

G = 10.0


def _falling_block_over_far_ground(gap=100.0):
    m = srdda.Model(gravity=(0.0, -G))
    m.add_material("rock", srdda.Material(density=2500.0, young=1e9, poisson=0.25))
    m.add_block([[-1, -gap - 1], [2, -gap - 1], [2, -gap], [-1, -gap]], "rock", fixed=True)
    m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "rock")
    return m


@pytest.mark.parametrize("method, rho", [("dda0", 1.0), ("dda1", 1.0), ("srdda", 1.0), ("srdda", 0.5)])
def test_free_fall_with_cut_steps_keeps_v_equal_g_t(method, rho):
    # w0 = 51 m (the model is 102 m high), g2 = 2e-6: a step may move 1e-4 m, so the 10 ms steps
    # get cut again and again.
    # Every scheme integrates constant acceleration exactly, whatever the step sizes: v = g t and
    # y = -g t²/2 to rounding (1e-12 relative).
    settings = srdda.RunSettings(dt=0.01, n_steps=60, method=method, rho_inf=rho, max_displacement_ratio=2e-6)
    res = srdda.run(_falling_block_over_far_ground(), settings)
    assert res.completed, res.status
    t = np.asarray(res.time)
    dts = np.diff(t)
    assert dts.min() < 0.5 * settings.dt  # steps were cut
    assert len(np.unique(np.round(dts, 15))) > 3  # and Δt varied
    v = res.array("velocity")[:, 1, 1]
    assert np.allclose(v, -G * t, rtol=1e-12, atol=1e-12)
    y = res.array("centroid")[:, 1, 1] - 0.5
    assert np.allclose(y, -0.5 * G * t**2, rtol=1e-10, atol=1e-12)


def test_step_displacement_never_exceeds_g2_w0():
    settings = srdda.RunSettings(dt=0.01, n_steps=40, max_displacement_ratio=2e-6)
    res = srdda.run(_falling_block_over_far_ground(), settings)
    moved = np.abs(np.diff(res.array("centroid")[:, 1, 1]))
    assert moved.max() <= 2e-6 * 51.0 * (1 + 1e-12)  # g2·w0, w0 = half of the 102 m model height


# Δt is cut down to 1e-7 s here: 2M/Δt² dwarfs the fixed block's identity rows, and scipy's
# dense solver warns about the condition number (the solutions are still used only to be rejected).
@pytest.mark.filterwarnings("ignore::scipy.linalg.LinAlgWarning")
def test_open_close_cap_cuts_and_then_stops_with_a_message():
    # The block rests on a frictionless base and moves sideways: its contacts start locked and
    # must turn to sliding, which needs a second solve at any Δt. With a cap of one solve the
    # step is cut until Δt falls below the minimum, and the run stops (never loops forever).
    m = srdda.Model(gravity=(0.0, -G))
    m.add_material("rock", srdda.Material(density=2500.0, young=1e9, poisson=0.25))
    m.add_block([[-2, -1], [2, -1], [2, 0], [-2, 0]], "rock", fixed=True)
    m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "rock", velocity=(1.0, 0.0))
    settings = srdda.RunSettings(dt=1e-3, n_steps=10, open_close_max_iterations=1, min_dt=1e-7)
    res = srdda.run(m, settings)
    assert res.status.startswith("stopped")
    assert "open-close did not converge" in res.status and "minimum" in res.status
    # the message says what flipped: the two locked corners of block 1 on the base (block 0) turning to sliding
    assert "(2 contacts still changing state, between blocks block 0/block 1 (2 contacts))" in res.status, res.status
    assert res.final_state.step == 0  # nothing accepted, nothing recorded but the start
    ok = srdda.run(m, srdda.RunSettings(dt=1e-3, n_steps=10))
    assert ok.completed


def _first_attempt(model, settings):
    arrays = model.arrays()
    stepper = Stepper(arrays, settings, get_solver())
    return stepper.step(initial_state(arrays, stepper.method), settings.dt)


def _sliding_block():
    m = srdda.Model(gravity=(0.0, -G))
    m.add_material("rock", srdda.Material(density=2500.0, young=1e9, poisson=0.25))
    m.add_block([[-2, -1], [2, -1], [2, 0], [-2, 0]], "rock", fixed=True)
    m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "rock", velocity=(1.0, 0.0))
    return m


def test_a_cut_says_its_cause():
    # the cause tells a solve that gave up (the open-close cap) from Δt too long for the contacts'
    # displacement bound: the bench counts cuts by it (srdda.term.CUT_CAUSES)
    capped = _first_attempt(_sliding_block(), srdda.RunSettings(dt=1e-3, n_steps=1, open_close_max_iterations=1))
    assert (capped.status, capped.cause) == ("cut", "iteration"), capped.reason
    far = _first_attempt(_falling_block_over_far_ground(),
                         srdda.RunSettings(dt=0.01, n_steps=1, max_displacement_ratio=2e-6))
    assert (far.status, far.cause) == ("cut", "displacement"), far.reason
    ok = _first_attempt(_sliding_block(), srdda.RunSettings(dt=1e-3, n_steps=1))
    assert (ok.status, ok.cause) == ("accepted", "")
    assert {capped.cause, far.cause} < set(CUT_CAUSES)


def test_contacts_are_committed_on_the_state():
    m = srdda.Model(gravity=(0.0, -G))
    m.add_material("rock", srdda.Material(density=2500.0, young=1e9, poisson=0.25))
    m.add_block([[-2, -1], [2, -1], [2, 0], [-2, 0]], "rock", fixed=True)
    m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "rock")
    res = srdda.run(m, srdda.RunSettings(dt=1e-3, n_steps=3))
    contacts = res.final_state.contacts
    assert isinstance(contacts, ContactSet) and len(contacts.key) == 2
    assert np.all(contacts.closed) and contacts.energy > 0


@pytest.mark.parametrize("field, value", [("max_displacement_ratio", 0.0), ("step_cut_factor", 1.0),
                                          ("open_close_max_iterations", 0), ("contact_penalty", -1.0),
                                          ("contact_angle_tolerance", 60.0)])
def test_bad_settings_are_refused_by_name(field, value):
    with pytest.raises(ValueError, match=field):
        srdda.RunSettings(dt=1e-3, n_steps=1, **{field: value})


def test_automatic_penalty_is_a_multiple_of_young():
    # plane stress: 1/C11 = E exactly
    arrays = _falling_block_over_far_ground().arrays()
    s = srdda.RunSettings(dt=1e-3, n_steps=1, auto_penalty=50.0, shear_ratio=0.5)
    p = srdda.step.contact_parameters(arrays, s, 51.0)
    assert p.normal_stiffness == pytest.approx(50.0 * 1e9, rel=1e-12)
    assert p.shear_stiffness == pytest.approx(25.0 * 1e9, rel=1e-12)
    assert p.distance == pytest.approx(2.5 * 0.01 * 51.0, rel=1e-12)  # d0 = 2.5 g2 w0


def test_contact_settings_round_trip_through_the_model_file(tmp_path):
    from srdda.io.modelfile import load_model, save_model

    settings = srdda.RunSettings(dt=1e-3, n_steps=5, contacts=True, contact_penalty=3e9, shear_ratio=0.25,
                                 max_displacement_ratio=0.002, contact_angle_tolerance=5.0,
                                 open_close_max_iterations=9, min_dt=1e-8)
    save_model(_falling_block_over_far_ground(), settings, tmp_path / "m.toml")
    _, loaded = load_model(tmp_path / "m.toml")
    assert loaded == settings


def _examples():
    from srdda.apps.paper import examples_dir

    return examples_dir()


def test_bad_contact_setting_in_a_model_file_names_the_field(tmp_path):
    from srdda.io.modelfile import ModelFileError, load_model

    text = (_examples() / "paper" / "rockfall.toml").read_text().replace(
        "max_displacement_ratio = 0.001", "max_displacement_ratio = 0")
    (tmp_path / "bad.toml").write_text(text)
    with pytest.raises(ModelFileError, match="max_displacement_ratio"):
        load_model(tmp_path / "bad.toml")
