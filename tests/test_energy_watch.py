"""The energy watch (issue 15, defect 9): a contact run whose ledger shows energy created warns once,
naming the step and the blocks; an energy-safe run never does. And the warning for a Δt far too large."""
import warnings

import numpy as np
import pytest

import srdda
import srdda.simulation as simulation
from srdda.simulation import EnergyWarning
from srdda.term import Term


class Booster(Term):
    """A push of 50 N along +x on every movable block that does not report its work: energy from nothing."""

    def add_to(self, system, ctx):
        system.rhs[:, ctx.block_type.translation.start] += 50.0


def _model():
    m = srdda.Model(gravity=(0.0, 0.0))
    m.add_material("rock", srdda.Material(2500.0, 1e9, 0.25))
    m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "rock", velocity=(1.0, 0.0), name="stone")
    m.add_block([[-5, -3], [60, -3], [60, -2], [-5, -2]], "rock", fixed=True)  # a contact model (never touched)
    return m


def test_energy_created_by_a_term_warns_once_with_step_and_block(monkeypatch):
    class BoostedStepper(simulation.Stepper):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            self.terms.append(Booster())

    monkeypatch.setattr(simulation, "Stepper", BoostedStepper)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        srdda.run(_model(), srdda.RunSettings(dt=1e-2, n_steps=100))
    created = [w for w in caught if issubclass(w.category, EnergyWarning)]
    assert len(created) == 1
    text = str(created[0].message)
    # 50 N on 2500 kg moving at 1 m/s: ΔE = 50·Δx ≈ 0.5 J per step on E(0) = 1250 J: the 1 %
    # threshold is passed at step 25 or 26 (the push also speeds the block up)
    step = int(text.split("at step ")[1].split()[0])
    assert 24 <= step <= 27 and "stone" in text


@pytest.mark.parametrize("method", ["dda0", "dda1", "srdda"])
def test_a_block_dropped_on_a_base_gives_no_energy_warning(method):
    m = srdda.Model(gravity=(0.0, -9.81))
    m.add_material("rock", srdda.Material(2600.0, 1e10, 0.25))
    m.add_joint_material("j", srdda.JointMaterial(friction_angle=30.0), between=[("rock", "rock")])
    m.add_block([[-10, -1], [10, -1], [10, 0], [-10, 0]], "rock", fixed=True)
    m.add_block(np.array([[0.0, 0.1], [0.4, 0.15], [0.1, 0.5]]), "rock", velocity=(1.0, 0.0), angular_velocity=2.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error", EnergyWarning)
        result = srdda.run(m, srdda.RunSettings(dt=1e-3, n_steps=600, method=method, penalty=1e11))
    assert result.completed


def _drop_model():
    m = srdda.Model(gravity=(0.0, -9.81))
    m.add_material("rock", srdda.Material(2600.0, 1e10, 0.25))
    m.add_block([[-10, -1], [10, -1], [10, 0], [-10, 0]], "rock", fixed=True)
    m.add_block([[0, 0.1], [1, 0.1], [1, 1.1], [0, 1.1]], "rock")
    return m


def test_a_time_step_far_too_large_for_a_contact_model_warns_once():
    # w0 = 1.05 m, g2 = 0.01: a step may move 0.0105 m, which a block falling from rest covers
    # in sqrt(2·0.0105/9.81) = 0.046 s; Δt = 1 s is 22 times that, 0.2 s only 4 times
    m = _drop_model()
    with pytest.warns(simulation.TimeStepWarning, match="far too large") as caught:
        srdda.run(m, srdda.RunSettings(dt=1.0, n_steps=2))
    assert len([w for w in caught if issubclass(w.category, simulation.TimeStepWarning)]) == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error", simulation.TimeStepWarning)
        srdda.run(m, srdda.RunSettings(dt=0.2, n_steps=2))
