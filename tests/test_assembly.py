"""The global matrix equals the plain sum of its 6×6 sub-matrices, whatever the storage."""
import numpy as np

from srdda.assembly.system import BlockSystem, PenaltyPairs, add_penalty_pairs


def _random_system(nb=7, npairs=15, seed=0):
    rng = np.random.default_rng(seed)
    system = BlockSystem(rng.normal(size=(nb, 6, 6)), np.zeros((nb, 6)))
    i = rng.integers(0, nb, npairs)
    j = (i + rng.integers(1, nb, npairs)) % nb  # never i
    blocks = rng.normal(size=(npairs, 6, 6))
    system.add_off_diagonal(i, j, blocks)
    system.add_off_diagonal(i[:4], j[:4], blocks[:4])  # repeated pairs must add up
    naive = np.zeros((nb * 6, nb * 6))
    for b in range(nb):
        naive[6 * b:6 * b + 6, 6 * b:6 * b + 6] += system.diag[b]
    for a, b, k in [*zip(i, j, blocks), *zip(i[:4], j[:4], blocks[:4])]:
        naive[6 * a:6 * a + 6, 6 * b:6 * b + 6] += k
        naive[6 * b:6 * b + 6, 6 * a:6 * a + 6] += k.T
    return system, naive


def test_sparse_and_dense_forms_equal_the_naive_sum():
    system, naive = _random_system()
    # sums of at most three O(1) numbers in another order: a few ulps
    assert np.allclose(system.to_csr().toarray(), naive, rtol=0, atol=1e-14)
    assert np.allclose(system.to_dense(), naive, rtol=0, atol=1e-14)


def test_penalty_pair_is_symmetric_and_pulls_the_gap_closed():
    # one spring k between block 0 (point at T0) and block 1 (point at T1): the
    # energy ½k|T0 d0 - T1 d1 + g|² has the gradient k[T0ᵀ(.), -T1ᵀ(.)]; the solve
    # of K d = -grad at d = 0 closes g exactly when both blocks are free to translate.
    system = BlockSystem(np.zeros((2, 6, 6)), np.zeros((2, 6)))
    T = np.zeros((1, 2, 6))
    T[0, 0, 0] = T[0, 1, 1] = 1.0
    gap = np.array([[0.3, -0.2]])
    add_penalty_pairs(system, PenaltyPairs(np.array([0]), T, np.array([1]), T, gap, np.array([5.0])), 1.0)
    A = system.to_csr().toarray()
    assert np.array_equal(A, A.T)
    # block 1 held: block 0 moves by -gap
    A[6:, :] = 0.0
    A[6:, 6:] = np.eye(6)
    A[:6, 2:6] += np.eye(6)[:, 2:6]  # the spring does not touch rotation and strain: fix them
    rhs = system.rhs.ravel().copy()
    rhs[6:] = 0
    d = np.linalg.solve(A, rhs)
    assert np.allclose(d[:2], -gap[0], atol=1e-15)


def test_scatter_add_is_np_add_at_bit_for_bit():
    # the compiled scatter adds in the same order as np.add.at, so the sums are the same bits
    from srdda.assembly.system import scatter_add
    rng = np.random.default_rng(3)
    index = rng.integers(0, 7, size=200)
    for shape in [(7, 6), (7, 6, 6), (7, 12, 12)]:
        values = rng.normal(size=(200, *shape[1:])) * 10.0 ** rng.integers(-8, 8, size=(200,) + (1,) * (len(shape) - 1))
        expected = rng.normal(size=shape)
        got = expected.copy()
        np.add.at(expected, index, values)
        scatter_add(got, index, values)
        assert np.array_equal(got, expected)
