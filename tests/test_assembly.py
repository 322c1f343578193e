"""The global matrix equals the plain sum of its 6×6 sub-matrices, whatever the storage."""
import numpy as np
import pytest

from srdda.assembly.system import BlockSystem, PenaltyPairs, _block_order, add_penalty_pairs


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


@pytest.mark.parametrize("threads", ["serial", "parallel"])
def test_block_sums_are_np_add_reduceat_bit_for_bit(threads):
    # to_bsr sums each (i, j) block's contributions in numpy's own order (the first, then the pairwise sum
    # of the rest), so the matrix has the bits of the np.add.reduceat it replaced; segment lengths cross
    # numpy's unrolled (8) and blocked (128) pairwise thresholds; a third of the blocks are read transposed;
    # large systems share the segments among threads, each still summed in that order; the blocks are read
    # from three arrays, the diagonal blocks, the first stack and the rest (to_bsr does not join them)
    from srdda.assembly.system import _segment_sums, _segment_sums_parallel
    rng = np.random.default_rng(4)
    lengths = np.concatenate([rng.integers(1, 12, 400), [8, 9, 10, 16, 17, 128, 129, 130, 257, 1000]])
    total = int(lengths.sum())
    blocks = rng.normal(size=(total, 6, 6)) * 10.0 ** rng.integers(-8, 8, size=(total, 1, 1))
    first = np.r_[0, np.cumsum(lengths)[:-1]]
    order = rng.permutation(total)
    flip = (rng.random(total) < 1 / 3).astype(np.int8)
    entries = np.arange(36)
    layouts = np.stack([entries, entries.reshape(6, 6).T.ravel()])
    got = np.empty((len(first), 36))
    sums = _segment_sums if threads == "serial" else _segment_sums_parallel
    split, second = total // 3, 2 * total // 3
    flat = blocks.reshape(total, 36)
    sums(flat[:split], flat[split:second], flat[second:], order, flip, layouts, first, got)
    sorted_blocks = blocks[order]
    sorted_blocks[flip == 1] = np.swapaxes(sorted_blocks[flip == 1], 1, 2)
    assert np.array_equal(got, np.add.reduceat(sorted_blocks, first, axis=0).reshape(len(first), 36))


def _penalty_by_einsum(system, pairs, factor):
    """add_penalty_pairs as whole-array einsums and np.add.at (the form the compiled pass replaced)."""
    k, ta = pairs.stiffness, pairs.t_a
    kta = k[:, None, None] * ta
    np.add.at(system.diag, pairs.block_a, factor * np.einsum("nki,nkj->nij", kta, ta))
    np.add.at(system.rhs, pairs.block_a, -np.einsum("nki,nk->ni", kta, pairs.gap))
    if pairs.t_b is None:
        return
    linked = pairs.block_b >= 0
    a, b, tb = pairs.block_a[linked], pairs.block_b[linked], pairs.t_b[linked]
    ktb = k[linked, None, None] * tb
    np.add.at(system.diag, b, factor * np.einsum("nki,nkj->nij", ktb, tb))
    np.add.at(system.rhs, b, np.einsum("nki,nk->ni", ktb, pairs.gap[linked]))
    cross = -factor * np.einsum("nki,nkj->nij", kta[linked], tb)
    same = a == b
    np.add.at(system.diag, a[same], cross[same] + np.swapaxes(cross[same], 1, 2))
    system.add_off_diagonal(a[~same], b[~same], cross[~same])


@pytest.mark.parametrize("threads", ["serial", "parallel"])
def test_compiled_penalty_pairs_equal_the_einsum_sums_bit_for_bit(threads, monkeypatch):
    # the paper's rows (the rockfall amplifies a last-bit change to 1e-6) depend on these sums being the
    # same bits: 1 to 3 rows per spring, 2D and 3D blocks, springs to the ground, within one block, repeated;
    # large systems share the blocks among threads (PARALLEL_BLOCKS), each block's sums still in spring order
    if threads == "parallel":
        monkeypatch.setattr("srdda.assembly.system.PARALLEL_BLOCKS", 0)
    rng = np.random.default_rng(6)
    for trial in range(60):
        nb, ndof, rows = 6, (6, 12)[trial % 2], 1 + trial % 3
        n = int(rng.integers(1, 40))
        a = rng.integers(0, nb, n)
        b = np.full(n, -1) if trial % 4 == 0 else rng.integers(-1, nb, n)
        ta = rng.normal(size=(n, rows, ndof))
        tb = None if trial % 5 == 0 else rng.normal(size=(n, rows, ndof))
        pairs = PenaltyPairs(a, ta, b, tb, rng.normal(size=(n, rows)), np.exp(rng.normal(size=n)))
        start = rng.normal(size=(nb, ndof, ndof))
        got, expected = (BlockSystem(start.copy(), np.zeros((nb, ndof))) for _ in range(2))
        add_penalty_pairs(got, pairs, 0.7)
        _penalty_by_einsum(expected, pairs, 0.7)
        assert np.array_equal(got.diag, expected.diag) and np.array_equal(got.rhs, expected.rhs)
        assert np.array_equal(got.to_bsr().toarray(), expected.to_bsr().toarray())


def test_held_blocks_are_identity_rows_without_couplings():
    # fix_blocks keeps the coupling stacks and leaves the held blocks' couplings out when the matrix is made:
    # the matrix is the naive sum with every row and column of a held block replaced by the identity's
    system, naive = _random_system(seed=2)
    held = np.array([True, False, False, True, False, False, False])
    system.fix_blocks(held)
    rows = np.repeat(held, 6)
    naive[rows, :] = 0.0
    naive[:, rows] = 0.0
    naive[rows, rows] = 1.0
    assert np.allclose(system.to_bsr().toarray(), naive, rtol=0, atol=1e-14)
    assert np.allclose(system.to_dense(), naive, rtol=0, atol=1e-14)


def test_coupling_blocks_picked_by_which_equal_the_picked_stack_bit_for_bit():
    # add_off_diagonal(..., which=k) leaves the other blocks of the stack out of the matrix (the open
    # contacts' zero blocks), without copying the stack: the same matrix as a stack of the picked blocks
    rng = np.random.default_rng(8)
    nb, ndof, n = 7, 6, 40
    bi = rng.integers(0, nb, n)
    bj = (bi + rng.integers(1, nb, n)) % nb
    blocks = rng.normal(size=(n, ndof, ndof))
    which = np.flatnonzero(rng.random(n) < 0.6)
    diag = rng.normal(size=(nb, ndof, ndof))
    picked, gathered = (BlockSystem(diag.copy(), np.zeros((nb, ndof))) for _ in range(2))
    picked.add_off_diagonal(bi, bj, blocks, which=which)
    gathered.add_off_diagonal(bi[which], bj[which], blocks[which])
    assert np.array_equal(picked.to_bsr().toarray(), gathered.to_bsr().toarray())
    assert np.array_equal(picked.to_dense(), gathered.to_dense())
    assert not np.array_equal(picked.to_dense(), BlockSystem(diag.copy(), np.zeros((nb, ndof))).to_dense())


@pytest.mark.parametrize("held", [None, np.array([True, False, False, True, False, False, False])])
def test_quadratic_form_is_x_dot_a_x(held):
    # the line search's curvature xᵀAx without the matrix: stacks whole and picked by `which`, with and
    # without held blocks (whose couplings drop out and whose rows are the identity's). Against the dense
    # matrix, whose sums come in another order: 1e-12 of the terms' magnitude Σ|x_i A_ij x_j|
    system, _ = _random_system(seed=4)
    rng = np.random.default_rng(5)
    extra = rng.normal(size=(9, 6, 6))
    bi = rng.integers(0, 7, 9)
    system.add_off_diagonal(bi, (bi + 1 + rng.integers(0, 6, 9)) % 7, extra, which=np.array([0, 3, 4, 8]))
    if held is not None:
        system.fix_blocks(held)
    x = rng.normal(size=(7, 6))
    dense = system.to_dense()
    scale = float(np.abs(x.ravel()) @ np.abs(dense) @ np.abs(x.ravel()))
    assert abs(system.quadratic_form(x) - x.ravel() @ dense @ x.ravel()) <= 1e-12 * scale


def test_block_order_is_a_stable_sort_of_the_block_keys():
    # to_bsr sums the blocks in this order, so it must be exactly numpy's stable sort of row·nb + col (the
    # order the matrix's bits were made with), with the groups of equal keys and the rows' pointers
    rng = np.random.default_rng(8)
    for trial in range(100):
        nb, m = int(rng.integers(1, 60)), int(rng.integers(0, 400))
        rows = np.concatenate([np.arange(nb), rng.integers(0, nb, m)])
        cols = np.concatenate([np.arange(nb), rng.integers(0, nb, m)])
        key = rows * nb + cols
        order = np.argsort(key, kind="stable")
        first = np.flatnonzero(np.r_[True, key[order][1:] != key[order][:-1]])
        group_rows, group_cols = np.divmod(key[order][first], nb)
        got = _block_order(rows, cols, nb)
        for a, b in zip(got, (order, first, group_cols, np.searchsorted(group_rows, np.arange(nb + 1)))):
            assert np.array_equal(a, b), trial
