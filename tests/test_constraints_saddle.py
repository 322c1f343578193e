"""The saddle-point system [[A, Cᵀ], [C, 0]]: assembly, backends, fixed blocks, redundant rows."""
import numpy as np
import pytest

from srdda import Material, Model, ModelError, RunSettings, run
from srdda.assembly.system import BlockSystem
from srdda.solvers import get_solver

# Blocks joined by a hinge share an edge; these tests are about the hinge alone, so the block-contact
# search (issue 3) is switched off where RunSettings has the switch.
NO_CONTACTS = {"contacts": False} if "contacts" in RunSettings.__dataclass_fields__ else {}


def _random_system(nb=5, seed=0):
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(nb, 6, 6))
    diag = np.einsum("nij,nkj->nik", q, q) + 6 * np.eye(6)  # SPD blocks
    system = BlockSystem(diag, rng.normal(size=(nb, 6)))
    t = rng.normal(size=(3, 2, 6))
    system.add_point_constraints(np.array([0, 1, 3]), t, np.array([1, -1, 4]), rng.normal(size=(3, 2, 6)),
                                 rng.normal(size=(3, 2)), components=np.array([[1, 1], [0, 1], [1, 0]], bool))
    return system


def test_saddle_matrix_is_the_block_matrix():
    s = _random_system()
    n, nc = s.size, s.n_constraints
    assert nc == 4
    K = s.saddle_dense()
    assert np.allclose(K, K.T)
    assert np.allclose(K[:n, :n], s.to_dense())
    assert np.allclose(K[n:, :n], s.constraint_matrix().toarray())
    assert np.allclose(K[n:, n:], 0.0)
    assert np.allclose(s.saddle_csr().toarray(), K)


@pytest.mark.parametrize("backend", ["dense", "superlu"])
def test_backends_solve_the_saddle_point(backend):
    s = _random_system()
    rhs = s.full_rhs()
    x = get_solver(backend).solve(s, rhs)
    # the KKT conditions: A Δd + Cᵀ μ = F and C Δd = g, to round-off of a well-conditioned system
    assert np.allclose(s.saddle_dense() @ x, rhs, atol=1e-10)


def test_fixed_block_columns_drop_out():
    s = _random_system()
    fixed = np.zeros(5, bool)
    fixed[4] = True
    s.fix_blocks(fixed)
    C = s.constraint_matrix().toarray()
    assert np.allclose(C[:, 24:30], 0.0)
    x = get_solver("superlu").solve(s, s.full_rhs())
    assert np.allclose(x[24:30], 0.0)


def _bar_model():
    m = Model(gravity=(0.0, -10.0))
    m.add_material("bar", Material(density=2500.0, young=1e10, poisson=0.25))
    m.add_block([[0, -0.05], [1, -0.05], [1, 0.05], [0, 0.05]], "bar")
    return m


def test_hinge_to_a_fixed_block_is_a_pin():
    m = _bar_model()
    m.add_block([[-1, -0.5], [0, -0.5], [0, 0.5], [-1, 0.5]], "bar", fixed=True)
    m.add_hinge((0.0, 0.0), block_a=0, block_b=1)
    res = run(m, RunSettings(dt=1e-3, n_steps=200, method="srdda", **NO_CONTACTS))
    assert res.completed
    assert np.allclose(res.final_state.points[0], [0.0, 0.0], atol=1e-12)
    assert res.final_state.rotation[0] < -0.1  # it swings


@pytest.mark.parametrize("backend", ["dense", "superlu"])
def test_conflicting_constraints_stop_with_a_message(backend, monkeypatch):
    m = _bar_model()
    m.add_pin((0.0, 0.0))
    m.add_pin((0.0, 0.0))  # the same pin twice: dependent rows, a singular saddle-point matrix
    with pytest.raises(ModelError, match="redundant constraints: 'pin 1' repeats what 'pin 0' already imposes"):
        m.arrays()  # the model check refuses it (issue 32); the solver's own guard is for what that check misses
    monkeypatch.setattr(Model, "_check_held", lambda self, arrays: None)
    res = run(m, RunSettings(dt=1e-3, n_steps=5, method="dda0", solver=backend))
    assert not res.completed
    assert "singular" in res.status and "step 1" in res.status


@pytest.mark.parametrize("scheme", ["shi", "paper", "chung-hulbert"])
def test_pin_exact_under_every_scheme(scheme):
    m = _bar_model()
    m.add_pin((0.0, 0.0))
    rho_inf = 1.0 if scheme == "shi" else 0.8  # Shi's scheme has no ρ∞ (settings reject it)
    res = run(m, RunSettings(dt=2e-3, n_steps=100, method="srdda", scheme=scheme, rho_inf=rho_inf))
    assert res.completed
    assert np.allclose(res.final_state.points[0], [0.0, 0.0], atol=1e-12)


def test_hinged_block_pairs():
    m = _bar_model()
    m.add_block([[1, -0.05], [2, -0.05], [2, 0.05], [1, 0.05]], "bar")
    m.add_pin((0.0, 0.0), block=0)
    m.add_hinge((1.0, 0.0), block_a=0, block_b=1)
    assert m.arrays().links.hinged_block_pairs.tolist() == [[0, 1]]
