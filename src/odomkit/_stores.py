"""Streaming (non-temporal) stores for the numba kernels that write long outputs.

A kernel that writes a (10^7, 3) pose track or a (10^7, 3, 3) covariance array writes
far more than any cache holds. An ordinary store first reads the cache line it writes
into (a "read for ownership"), so every output byte crosses the memory bus twice. A
non-temporal store (x86 ``movnt``; LLVM's ``!nontemporal``) writes whole lines straight
to memory instead, as glibc's ``memcpy`` and ``memset`` do for large copies. Measured on
the dead-reckoning kernel's 240 MB output: 7 ms instead of 18 ms.

The lines do not stay in the cache, so these stores pay only when the output is larger
than the cache; the kernels use them above a size threshold. x86 orders non-temporal
stores weakly: a kernel that used them ends with :func:`store_fence`.

Importing this module imports numba and llvmlite; only kernel modules import it.
"""

from __future__ import annotations

import platform
from typing import Any

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.core.errors import TypingError
from numba.core.extending import intrinsic

__all__ = ["store_fence", "stream_store"]

_X86 = platform.machine().lower() in ("x86_64", "amd64", "i386", "i686")


def _stream_store(typingctx: Any, array: Any, i: Any, j: Any, value: Any) -> Any:
    """``stream_store(array, i, j, value)``: ``array[i, j] = value`` for a 2-D float64
    array, as a non-temporal store.

    No bounds check and no negative-index wraparound: the caller guarantees
    ``0 <= i < array.shape[0]`` and ``0 <= j < array.shape[1]``.
    """
    if not (isinstance(array, types.Array) and array.ndim == 2 and array.dtype == types.float64):
        raise TypingError(f"stream_store needs a 2-D float64 array, got {array}")
    sig = types.void(array, i, j, types.float64)

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        arr, row, col, val = args
        aryty = signature.args[0]
        ary = context.make_array(aryty)(context, builder, arr)
        ptr = cgutils.get_item_pointer(context, builder, aryty, ary, [row, col], wraparound=False)
        val = context.cast(builder, val, signature.args[3], types.float64)
        store = builder.store(val, ptr)
        store.set_metadata("nontemporal", builder.module.add_metadata([ir.IntType(32)(1)]))
        return context.get_dummy_value()

    return sig, codegen


def _store_fence(typingctx: Any) -> Any:
    """``store_fence()``: order all earlier (streaming) stores before any later one:
    ``sfence`` on x86, as glibc's non-temporal ``memcpy`` ends; a full fence elsewhere."""
    sig = types.void()

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        if _X86:
            fn = cgutils.get_or_insert_function(builder.module, ir.FunctionType(ir.VoidType(), []),
                                                "llvm.x86.sse.sfence")
            builder.call(fn, [])
        else:
            builder.fence("seq_cst")
        return context.get_dummy_value()

    return sig, codegen


# Typed Any: a numba intrinsic is called without the typing context its definition takes.
stream_store: Any = intrinsic(_stream_store)
store_fence: Any = intrinsic(_store_fence)
