"""The work arrays of the carried sensitivities (scoutsim._core.numerics.tangent_work).

Law checked: packing is lossless. A run carries the arrays packed into two buffers; the
compiled code's views of them must be the arrays packed.
"""

from __future__ import annotations

import numba
import numpy as np

from scoutsim._core.numerics import tangent_work as T


def _leaves(tree):
    for x in tree:
        yield from _leaves(x) if isinstance(x, tuple) else (x,)


def test_packed_work_arrays_unpack_to_the_same_arrays():
    """A run carries its work arrays packed into two buffers (``TangentPack``); the
    compiled code's views of them must be the arrays packed, part for part, in shape, type
    and content (a part read at another's offset would silently differentiate garbage)."""
    rng = np.random.default_rng(3)
    parameters = (rng.normal(size=(2, 9)), rng.normal(size=(2, 4)), rng.normal(size=(2, 3)))
    work = T.tangent_work(3, 2, 5, (1e-6, 1e-8), (9, 4, 3), (*parameters, np.ones(2)))
    # every array filled with numbers of its own (a shifted part would show)
    for k, leaf in enumerate(_leaves(work)):
        if isinstance(leaf, np.ndarray):
            leaf[...] = (100 * k + rng.integers(0, 99, size=leaf.shape)).astype(leaf.dtype)
    pack = T.packed(work)
    unpacked = numba.njit(lambda p: T.unpacked(p))(pack)
    assert type(unpacked) is type(work)
    expected, got = list(_leaves(work)), list(_leaves(unpacked))
    assert len(got) == len(expected)
    for a, b in zip(expected, got):
        assert np.shape(a) == np.shape(b)
        assert np.asarray(a).dtype.kind == np.asarray(b).dtype.kind
        assert np.array_equal(a, b)
