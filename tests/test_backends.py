"""The conjugate gradient on an array backend (issue 34): numpy here, CuPy where a CUDA GPU is present.

Every test that takes the ``backend`` fixture runs twice: on numpy (always: the array-generic code CI
can run) and on CuPy, which is skipped with its reason where there is no GPU. On numpy the "GPU"
path of a run is the same code with numpy arrays: ``cupy_backend`` and ``gpu_problem`` are replaced
by the numpy backend for the test.

The systems are those of real steps: brick walls in 2D and 3D (English bond) whose coupling blocks
are stiff contact penalties (docs/performance.md, *The linear solve*), solved in the order a run
solves them (warm-started from one another).
"""
from __future__ import annotations

import copy
import dataclasses

import numba
import numpy as np
import pytest
from click.testing import CliRunner
from pydantic import ValidationError

import srdda
from srdda.apps import cli
from srdda import simulation
from srdda.assembly.system import BlockSystem
from srdda.backends import arrays as arrays_module
from srdda.solvers import _gpu as cg_module
from srdda.backends.arrays import (GPU_MIN_UNKNOWNS, ArrayBackend, GpuUnavailable, cupy_backend, gpu_problem,
                                   numpy_backend, resolve_device)
from srdda.apps.bench.models import brick_wall, english_bond_wall
from srdda.apps.bench.runner import BenchCase, format_table, measure
from srdda.settings import RunSettings
from srdda.solvers import (ArrayConjugateGradient, AutoSolver, BlockJacobi, BlockPatternCSR, ConjugateGradientSolver,
                           IterativeSolverError, SuperLUSolver, block_diagonal_csr, get_solver, gpu_solver)
from srdda.solvers._gpu import spd_inverses
from srdda.state import initial_state
from srdda.step import Stepper

NO_GPU = gpu_problem()
ON_GPU = pytest.param("cupy", marks=pytest.mark.skipif(NO_GPU is not None, reason=f"no CUDA GPU here: {NO_GPU}"))


@pytest.fixture(params=["numpy", ON_GPU])
def backend(request, monkeypatch) -> ArrayBackend:
    """The array backend of the test; on numpy, runs asked for ``device="gpu"`` use it too."""
    if request.param == "cupy":
        return cupy_backend()
    monkeypatch.setattr(arrays_module, "gpu_problem", lambda: None)
    monkeypatch.setattr(cg_module, "cupy_backend", numpy_backend)
    return numpy_backend()


class _Recorded:
    """A solver that solves with SuperLU (the run follows the direct path) and keeps a copy of every system as it
    came, and its solution (a copy: the contact springs summed by changes are updated in place by later solves,
    and a direct solve sums kept springs); ``keep_springs``: it takes the contact springs unsummed, as the
    device's CG does."""

    name = "recorded"

    def __init__(self, keep_springs: bool = False) -> None:
        self.direct = SuperLUSolver()
        self.keep_springs = keep_springs
        self.solves: list[tuple[BlockSystem, np.ndarray, np.ndarray]] = []

    def takes_springs(self, n_blocks: int) -> bool:
        return self.keep_springs

    def solve(self, system: BlockSystem, rhs: np.ndarray) -> np.ndarray:
        kept = copy.deepcopy(system)
        x = self.direct.solve(system, rhs)
        self.solves.append((kept, rhs, x))
        return x


def _step_systems(model, settings, steps: int = 2, stiffness_factor: float = 1.0, keep_springs: bool = False):
    """Every (system, rhs, exact solution) that ``steps`` steps of ``model`` solve."""
    k = settings.contact_penalty * stiffness_factor
    settings = dataclasses.replace(settings, contact_penalty=k, penalty=k)
    arrays = model.arrays()
    recorded = _Recorded(keep_springs)
    stepper = Stepper(arrays, settings, recorded)
    state, dt = initial_state(arrays, stepper.method), settings.dt
    for _ in range(steps):
        outcome = stepper.step(state, dt)
        assert outcome.status != "diverged", outcome.reason
        state = outcome.state if outcome.status == "accepted" else state
        dt = outcome.dt_next
    return recorded.solves


WALLS = {"2d": lambda: brick_wall(8, 6), "3d": lambda: english_bond_wall(3, 3)}


def _host(backend: ArrayBackend, matrix) -> object:
    return matrix.get() if backend.name == "cupy" else matrix


@pytest.mark.parametrize("wall", WALLS)
def test_the_device_matrix_is_the_assembled_matrix_entry_for_entry(backend, wall):
    solves = _step_systems(*WALLS[wall](), steps=5)
    patterns = {}
    for system, _, _ in solves:
        bsr = system.to_bsr()
        patterns[(bsr.indptr.tobytes(), bsr.indices.tobytes())] = bsr
    assert len(patterns) >= 2  # contacts opened or closed between solves: more than one block pattern
    for bsr in patterns.values():
        pattern = BlockPatternCSR(backend, bsr.indptr, bsr.indices, bsr.blocksize[0])
        device = _host(backend, pattern.load(backend.to_device(bsr.data)))
        expected = bsr.tocsr()
        # the same entries at the same places, bit for bit (a scatter of the values, no arithmetic)
        assert device.shape == expected.shape and device.nnz == expected.nnz
        assert np.array_equal(device.indptr, expected.indptr) and np.array_equal(device.indices, expected.indices)
        assert np.array_equal(device.data, expected.data)


def test_the_device_preconditioner_is_block_jacobi(backend):
    system, rhs, _ = _step_systems(*WALLS["3d"]())[0]
    jacobi = BlockJacobi(system.diag)
    inverse = block_diagonal_csr(backend, system.n_blocks, system.ndof)
    inverse.data = backend.to_device(jacobi.inverse).reshape(-1)
    applied = backend.to_host(inverse @ backend.to_device(rhs))
    # the same products summed in another order: equal to round-off of the largest term
    assert np.abs(applied - jacobi(rhs)).max() <= 1e-12 * np.abs(jacobi.inverse).max() * np.abs(rhs).max()


@pytest.mark.parametrize("wall", WALLS)
def test_kept_springs_make_the_assembled_matrix(wall):
    """A step whose solver takes the contact springs unsummed solves the same systems: the kept springs summed
    into blocks give the matrix the CPU assembles, the right-hand side has their pull-back forces, and the
    line search's curvature xᵀAx reads them without summing."""
    model, settings = WALLS[wall]()
    # the first step and the first solve of the second, where closed contacts pull back. Later solves part by
    # more than round-off: a sliding contact's friction follows its slip's direction, and slips of 1e-15 m
    # turn with increments 1e-20 m apart (measured on the 3D wall: 8e-9 of the largest force, step 2)
    first = len(_step_systems(model, settings, steps=1))
    summed = _step_systems(model, settings, steps=2)[: first + 1]
    kept = _step_systems(model, settings, steps=2, keep_springs=True)[: first + 1]
    assert len(kept) == len(summed) >= 3
    rng = np.random.default_rng(1)
    for (system, rhs, x), (reference, rhs_ref, x_ref) in zip(kept, summed):
        assert system.springs and not reference.springs and not system.pair_blocks
        dense, expected = copy.deepcopy(system).to_dense(), reference.to_dense()
        # the same springs from the same rows: equal bits on the 3D wall (20 blocks: summed afresh, in the same
        # order); the 2D wall's 52 blocks are summed by changes (1.3e-16 of the largest entry apart, measured).
        # The bound is round-off of the largest entry
        scale = np.abs(expected).max()
        assert np.abs(dense - expected).max() <= 1e-12 * scale
        assert np.abs(rhs - rhs_ref).max() <= 1e-12 * np.abs(rhs_ref).max()
        assert np.abs(x - x_ref).max() <= 1e-9  # the same solution, to the solver tolerance δ
        probe = rng.standard_normal((system.n_blocks, system.ndof))
        form = system.quadratic_form(probe)
        assert system.springs  # read without summing them
        assert form == pytest.approx(probe.ravel() @ expected @ probe.ravel(), rel=1e-12)


@pytest.mark.parametrize("wall", WALLS)
def test_the_device_applies_kept_springs_as_the_assembled_matrix(backend, wall):
    """The device's product B·x + Rᵀ(w ⊙ R·x) and its block-Jacobi inverse equal the CPU's assembled matrix and
    inverse on every system of two steps, and its solves meet the tolerance of the direct solve."""
    solves = _step_systems(*WALLS[wall](), keep_springs=True)
    solver = ArrayConjugateGradient(backend, 1e-9)
    rng = np.random.default_rng(2)
    for system, rhs, exact in solves:
        summed = copy.deepcopy(system)
        matrix = summed.to_bsr()
        springs = solver._device_springs(system)
        weights = [device.weights(stack) for device, stack in zip(springs, system.springs)]
        probe = rng.standard_normal(system.size)
        rest = system.to_bsr(springs=False)
        applied = backend.to_host(sum((device.apply(backend.to_device(probe), w)
                                       for device, w in zip(springs, weights)), backend.to_device(rest @ probe)))
        expected = matrix @ probe
        assert np.abs(applied - expected).max() <= 1e-12 * np.abs(matrix.data).max() * np.abs(probe).max() * 20
        diag = backend.to_device(system.diag.copy())
        for device, w in zip(springs, weights):
            device.add_diagonal(diag, w)
        inverse = backend.to_host(spd_inverses(backend, diag))
        reference = BlockJacobi(summed.diag).inverse
        assert np.abs(inverse - reference).max() <= 1e-9 * np.abs(reference).max()
        x = solver.solve(copy.deepcopy(system), rhs)
        assert np.abs(x - exact).max() <= 1e-9  # the stopping rule's promise
    assert solver.pattern_builds == 1  # B is block-diagonal throughout: one pattern


def test_a_device_solve_with_kept_springs_and_coupling_blocks_leaves_the_system_as_it_was(backend):
    """Newton's 3D steps add coupling blocks beside the kept springs (the slipping contacts' tangent springs):
    the device sums the springs into its own copy of the diagonal blocks, and its solves meet δ. On numpy the
    upload is the host array itself: summing into it changed the system that the line search then read
    (found by a 3D Newton run whose line search saw a curvature 60 times too large)."""
    model, settings = english_bond_wall(5, 3)
    solves = _step_systems(model, dataclasses.replace(settings, contact_solver="newton"), steps=1, keep_springs=True)
    coupled = [(system, rhs, exact) for system, rhs, exact in solves if system.pair_blocks and system.springs]
    assert coupled  # slipping contacts with a tangent spring in the first step (measured: 3 of 5 solves)
    solver = ArrayConjugateGradient(backend, 1e-9)
    for system, rhs, exact in coupled:
        diag, pairs = system.diag.copy(), [blocks.copy() for blocks in system.pair_blocks]
        x = solver.solve(system, rhs)
        assert np.array_equal(system.diag, diag)
        assert all(np.array_equal(a, b) for a, b in zip(system.pair_blocks, pairs))
        assert np.abs(x - exact).max() <= 1e-9


def test_a_block_that_is_not_positive_definite_is_named_on_the_device(backend):
    blocks = np.stack([np.eye(3), np.diag([1.0, -1.0, 1.0]), np.eye(3)])
    with pytest.raises(IterativeSolverError, match="diagonal block 1 "):
        spd_inverses(backend, backend.to_device(blocks))
    inverse = backend.to_host(spd_inverses(backend, backend.to_device(np.stack([2.0 * np.eye(3)] * 2))))
    assert np.allclose(inverse, 0.5 * np.eye(3), rtol=0, atol=1e-15)


@pytest.fixture
def two_threads():
    """The compiled CG's parallel sums, so its path through a stiff solve, depend on the thread count: the
    iteration bounds below were measured with 2 threads (the lent GPU machine has 16: there they failed)."""
    before = numba.get_num_threads()
    numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
    yield
    numba.set_num_threads(before)


@pytest.mark.parametrize("wall", WALLS)
@pytest.mark.parametrize("stiffness_factor", [1.0, 50.0])
def test_the_array_cg_solves_every_step_system_as_the_compiled_cg(backend, wall, stiffness_factor, two_threads):
    tolerance = 1e-9
    device = ArrayConjugateGradient(backend, tolerance)
    compiled = ConjugateGradientSolver("jacobi", tolerance)
    solves = _step_systems(*WALLS[wall](), stiffness_factor=stiffness_factor)
    assert len(solves) >= 3
    for system, rhs, exact in solves:  # in the run's order: each warm-started from the last solution
        x = device.solve(system, rhs)
        y = compiled.solve(system, rhs)
        # the stopping rule's promise, for both: every unknown within the tolerance of the direct solve
        assert np.abs(x - exact).max() <= tolerance and np.abs(y - exact).max() <= tolerance
    # the same iteration summed in another order. With contacts 20 times the inertia term it takes the same
    # iterations (measured: identical on both walls); 1,000 times stiffer, finite precision loses the
    # conjugacy of the directions and the two orders of the sums follow other paths, so single solves part
    # (measured up to 26 of 422 iterations apart, and 22 of 154 on one of the 3D wall's 23 solves since its
    # shear springs stay on the material) while the work over the run agrees (1.2 % on the 3D wall): there
    # the total is what the two must share, and each solve meets the tolerance (above)
    assert len(device.iterations) == len(compiled.iterations)
    if stiffness_factor == 1.0:
        assert device.iterations == compiled.iterations
    assert abs(sum(device.iterations) - sum(compiled.iterations)) <= 0.05 * sum(compiled.iterations)
    assert sum(device.iterations) > len(solves)  # the solves iterated (not all warm-started at the answer)


def test_a_block_pattern_moves_to_the_device_once(backend):
    system, rhs, _ = _step_systems(*WALLS["2d"]())[0]
    solver = ArrayConjugateGradient(backend, 1e-9)
    solver.solve(system, rhs)
    first = solver.uploaded_bytes
    solver.solve(system, 1.001 * rhs)
    bsr = system.to_bsr()
    # the second solve moves the values, the inverse blocks, the right-hand side and the start; not the pattern
    values = bsr.data.nbytes + system.diag.nbytes + 2 * rhs.nbytes
    assert solver.pattern_builds == 1 and solver.uploaded_bytes - first == values
    assert first == values + bsr.indptr.nbytes + bsr.indices.nbytes


def _final_positions(model, settings, **changes) -> tuple[np.ndarray, int]:
    result = simulation.run(model.arrays(), dataclasses.replace(settings, **changes), keep_history=False)
    assert result.status == "completed"
    return result.final_state.vertices, result.final_state.step


@pytest.mark.parametrize("model, solver", [(lambda: brick_wall(24, 24), "auto"),  # 589 blocks: auto iterates
                                           (lambda: english_bond_wall(5, 3), "cg-jacobi")], ids=["2d", "3d"])
def test_twenty_steps_on_the_device_end_where_the_cpu_path_ends(backend, model, solver):
    built, settings = model()
    settings = dataclasses.replace(settings, n_steps=20, solver=solver)
    cpu, steps = _final_positions(built, settings, device="cpu")
    direct, _ = _final_positions(built, settings, device="cpu", solver="superlu")
    gpu, _ = _final_positions(built, settings, device="gpu")
    bound = steps * settings.solver_tolerance
    # each step's increment is within the tolerance of the exact one on both paths, and positions are sums of
    # the steps' increments: 20 steps apart by at most 20 tolerances if every error added up. That holds only
    # where no contact's state hinges on a difference of that size: the CPU's own paths (the CG's and the
    # direct solver's) must agree to it first. The 35-block wall english_bond_wall(4, 4) has such a contact
    # (its CG path ends 5.2e-8 m from the direct one's, and an H200's CG path on the direct one's side); this
    # 32-block wall's paths agree to 2.3e-11 m, the 2D wall's to 5.6e-9 m (the device path, numpy: 6.4e-9 m in 2D)
    assert steps == 20
    assert np.abs(cpu - direct).max() <= bound / 2, "the CPU's own paths differ: no reference for the device"
    assert np.abs(gpu - cpu).max() <= bound, f"{np.abs(gpu - cpu).max():.3g} m from the CPU path, " \
        f"{np.abs(gpu - direct).max():.3g} m from the direct one's"


def test_auto_takes_the_gpu_for_large_models_only_when_one_is_present(monkeypatch):
    monkeypatch.setattr(arrays_module, "gpu_problem", lambda: None)
    assert resolve_device("auto", "auto", GPU_MIN_UNKNOWNS) == "gpu"
    assert resolve_device("auto", "cg-jacobi", GPU_MIN_UNKNOWNS) == "gpu"
    assert resolve_device("auto", "auto", GPU_MIN_UNKNOWNS - 1) == "cpu"
    assert resolve_device("auto", "superlu", GPU_MIN_UNKNOWNS) == "cpu"  # no GPU backend: the CPU
    assert resolve_device("cpu", "auto", GPU_MIN_UNKNOWNS) == "cpu"
    # measured (docs/gpu.md): the 10,051-block 2D wall ran slower on an H200 than on its machine's 16 cores, the
    # 3D wall of 10,000 blocks faster
    two_d, three_d = brick_wall(24, 24)[0].arrays(), english_bond_wall(3, 3)[0].arrays()
    assert resolve_device("auto", "auto", 10_051 * two_d.block_type.ndof) == "cpu"
    assert resolve_device("auto", "auto", 10_000 * three_d.block_type.ndof) == "gpu"
    monkeypatch.setattr(arrays_module, "gpu_problem", lambda: "CuPy is not installed")
    assert resolve_device("auto", "auto", 10 * GPU_MIN_UNKNOWNS) == "cpu"


def test_a_gpu_asked_for_where_there_is_none_is_one_clear_error(monkeypatch, tmp_path):
    reason = "CuPy is not installed: pip install srdda[gpu] (CUDA 12) or srdda[gpu-cuda13] (CUDA 13)"
    monkeypatch.setattr(arrays_module, "gpu_problem", lambda: reason)
    monkeypatch.setattr(cli, "gpu_problem", lambda: reason)
    settings = RunSettings(dt=1e-3, n_steps=1, device="gpu")  # a stored GPU run's settings still read anywhere
    with pytest.raises(GpuUnavailable, match=r"device = 'gpu' was asked for, but CuPy is not installed"):
        settings.resolved_device(10)
    with pytest.raises(GpuUnavailable, match="device = 'gpu'"):
        srdda.run(brick_wall(1, 1)[0], settings)
    with pytest.raises(GpuUnavailable, match="no GPU: CuPy is not installed"):
        get_solver("auto", device="gpu")
    model = tmp_path / "wall.toml"
    srdda.io.save_model(*brick_wall(2, 1), model)
    out = CliRunner().invoke(cli.main, ["run", str(model), "--device", "gpu", "--out", str(tmp_path / "o")])
    assert out.exit_code == 2 and "device = 'gpu' was asked for, but CuPy is not installed" in out.output
    assert not (tmp_path / "o").exists()  # nothing was written
    out = CliRunner().invoke(cli.main, ["bench", "--model", "slope_a", "--device", "gpu"])
    assert out.exit_code == 2 and "--device gpu: CuPy is not installed" in out.output
    out = CliRunner().invoke(cli.main, ["info"])
    assert out.exit_code == 0 and f"gpu: none ({reason})" in out.output


def test_a_gpu_with_a_solver_that_has_no_gpu_backend_names_both():
    with pytest.raises(ValidationError, match="device = 'gpu' runs the block-Jacobi conjugate gradient"):
        RunSettings(dt=1e-3, n_steps=1, device="gpu", solver="superlu")
    with pytest.raises(ValueError, match="solver 'superlu' has no GPU backend"):
        gpu_solver("superlu", backend=numpy_backend())
    with pytest.raises(ValueError, match="unknown device 'tpu'"):
        get_solver("auto", device="tpu")


def test_auto_on_the_gpu_keeps_small_and_constrained_systems_on_the_cpu(backend):
    auto = gpu_solver("auto", backend=backend)
    assert isinstance(auto, AutoSolver) and isinstance(auto.iterative, ArrayConjugateGradient)
    assert auto.iterative.backend.name == backend.name
    assert gpu_solver("cg-jacobi", backend=backend).backend.name == backend.name


def test_a_bench_row_on_the_device_says_where_and_how_much(backend):
    case = BenchCase("wall_589", 2, lambda: brick_wall(24, 24), steps=2, quick_steps=1)
    row = measure(case, 2, "dda0", None, timeout=120.0, device="gpu")
    assert row["status"] == "completed", row["note"]
    assert row["device"] == backend.device_name() and row["cg_iterations"] > 0
    assert row["gpu_upload_mb"] > 0.0
    if backend.name == "cupy":
        assert row["gpu_peak_mb"] > 0.0 and row["device"] != "cpu"
    else:
        assert row["gpu_peak_mb"] is None
    table = format_table([row, {**row, "device": "NVIDIA H100 80GB HBM3", "gpu_peak_mb": 12.5}])
    header, _, gpu_line = table.splitlines()
    assert "device" in header and "GPU MB" in header and "NVIDIA H100 80GB HBM3" in gpu_line and "12" in gpu_line
    assert "GPU MB" not in format_table([{**row, "device": "cpu"}])  # CPU rows keep the CPU table


def test_a_gpu_runs_results_read_anywhere_and_resume_only_on_a_gpu(monkeypatch, tmp_path):
    monkeypatch.setattr(arrays_module, "gpu_problem", lambda: None)
    monkeypatch.setattr(cg_module, "cupy_backend", numpy_backend)  # the "GPU" run on numpy
    model = tmp_path / "wall.toml"
    srdda.io.save_model(*brick_wall(2, 1), model)
    out = CliRunner().invoke(cli.main, ["run", str(model), "--device", "gpu", "--steps", "2", "--quiet",
                                        "--out", str(tmp_path / "o")])
    assert out.exit_code == 0, out.output
    results = tmp_path / "o" / "results.h5"
    monkeypatch.setattr(arrays_module, "gpu_problem", lambda: "CuPy found no CUDA device")
    assert srdda.read_results(results).settings.device == "gpu"  # the results read without a GPU
    before = results.read_bytes()
    out = CliRunner().invoke(cli.main, ["run", "--resume", str(results)])
    assert out.exit_code == 2 and "device = 'gpu' was asked for, but CuPy found no CUDA device" in out.output
    assert "Traceback" not in out.output and results.read_bytes() == before  # nothing written was damaged
