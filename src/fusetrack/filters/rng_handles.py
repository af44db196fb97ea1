"""NumPy generators inside Numba kernels, as plain integers.

Handing a :class:`numpy.random.Generator` to a Numba function costs 20-50 us per generator per
call (Numba builds its type and unboxes its ctypes interface every time), and a
``numba.typed.List`` of generators compiles for about 9 s in every new process (that type does
not cache). Here a generator is reduced, once, to four integers from NumPy's documented C
interface of its bit generator (``bit_generator.ctypes``: the address of its state and of its
``next_uint64``, ``next_uint32`` and ``next_double`` functions), a row of a ``(K, 4)`` ``uint64``
array (:func:`generator_handles`). Inside a kernel, :func:`_bitgen` rebuilds from a row the
struct Numba itself builds when it unboxes a bit generator, so Numba's implementations of NumPy's
distributions run on it: :func:`random_standard_normal` is NumPy's ziggurat (the numbers of
``Generator.standard_normal``, bit for bit; tested) and :func:`next_double` those of
``Generator.random``. The kernels' arguments are plain arrays, so they cache on disk like any
other (no compile in a new process), and a call costs nothing per generator.

Safety: the handles are raw pointers into the bit generators, valid while those objects live;
:class:`RunStreams` keeps the generators with their handles. A kernel must advance each
generator from one thread only, and NumPy's per-generator lock is not taken: do not draw from
the same generators in other Python threads during a call.
"""

from __future__ import annotations

import ctypes
import operator
from collections.abc import Sequence

import numpy as np
from numba import types
from numba.core import cgutils
from numba.core.extending import intrinsic
from numba.np.random.distributions import random_standard_normal
from numba.np.random.generator_core import next_double
from numpy.typing import NDArray

__all__ = [
    "RunStreams",
    "bitgen_from_handle",
    "generator_handles",
    "next_double",
    "random_standard_normal",
]


def _address(fn: object) -> int:
    value = ctypes.cast(fn, ctypes.c_void_p).value  # type: ignore[arg-type]
    return int(value or 0)


def generator_handles(gens: Sequence[np.random.Generator]) -> NDArray[np.uint64]:
    """``(R, 4)`` rows ``[state, next_uint64, next_uint32, next_double]`` (addresses) of the
    generators' bit generators, from NumPy's ``bit_generator.ctypes`` interface."""
    out = np.empty((len(gens), 4), dtype=np.uint64)
    for j, g in enumerate(gens):
        c = g.bit_generator.ctypes
        out[j] = (
            int(c.state_address),
            _address(c.next_uint64),
            _address(c.next_uint32),
            _address(c.next_double),
        )
    return out


class RunStreams:
    """The handles of a sequence of generators, with the generators (which keep the pointed-to
    states alive). :meth:`matches` tells whether another sequence holds the same objects;
    ``distinct`` whether no bit generator appears twice (two threads must never advance one)."""

    def __init__(self, gens: Sequence[np.random.Generator]) -> None:
        self.gens = tuple(gens)
        self.handles = generator_handles(self.gens)
        self.distinct = len({int(h) for h in self.handles[:, 0]}) == len(self.gens)

    def matches(self, gens: Sequence[np.random.Generator]) -> bool:
        return len(gens) == len(self.gens) and all(map(operator.is_, gens, self.gens))


@intrinsic
def _bitgen(tyctx, handle):  # pragma: no cover - compile time
    """Numba's bit-generator struct (what unboxing a ``BitGenerator`` builds) from one row of
    :func:`generator_handles`."""
    bg_type = types.NumPyRandomBitGeneratorType("bit_generator")
    sig = bg_type(handle)

    def codegen(ctx, builder, sig, args):
        row = ctx.make_array(sig.args[0])(ctx, builder, args[0])

        def item(i: int):
            idx = [ctx.get_constant(types.intp, i)]
            return builder.load(cgutils.get_item_pointer(ctx, builder, sig.args[0], row, idx))

        bg = cgutils.create_struct_proxy(bg_type)(ctx, builder)
        bg.parent = cgutils.get_null_value(bg.parent.type)
        bg.state_address = item(0)
        bg.state = item(0)
        bg.fnptr_next_uint64 = item(1)
        bg.fnptr_next_uint32 = item(2)
        bg.fnptr_next_double = item(3)
        bg.bit_generator = ctx.get_constant(types.uintp, 0)
        return bg._getvalue()

    return sig, codegen


bitgen_from_handle = _bitgen  # the public name (fusetrack.estimation's kernels use it)
