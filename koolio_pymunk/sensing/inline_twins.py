"""Inline twins of compiled functions: the same Python code compiled into its caller.

A numba call that passes arrays costs an atomic increment and decrement of each array's
reference count (``NRT_incref``/``NRT_decref``), and each call made inside the callee
pays it again; on the readings' hot paths these were a third of the perf samples
(``docs/speed.md``). :func:`inline_twin` compiles a function's own Python code a second
time with ``inline="always"``, so numba pastes its body into each compiled caller, and
can point the names it calls at twins of their own, so that a whole call tree lands in
one compiled function. The twin runs the same operations in the same order as the
original (no fastmath), so it gives the same bits; there is still one Python source of
each computation. The original stays as it was for Python callers and the rest of the
code.

numba's on-disk cache keys a compiled function on its own source file only, so a change
to a function inlined elsewhere would leave its callers' cached machine code as it was:
:mod:`koolio_pymunk.store.kernel_cache` clears the package's cached kernels whenever a
source that uses numba changed (every kernel module calls it at import).
"""

from __future__ import annotations

import types

import numba

from ..store.kernel_cache import ensure_fresh

ensure_fresh()  # numba's cache, in step with every kernel's source (see there)


def inline_twin(kernel, **callees):
    """An ``inline="always"`` copy of the compiled function ``kernel``: its Python code
    (``kernel.py_func``) with the global names in ``callees`` bound to other functions
    (inline twins of what it calls), the rest of its module's globals as they are now.

    The twin is only ever pasted into compiled callers (not cached on its own: its code
    object is the original's, and so would be its cache file)."""
    f = kernel.py_func
    scope = dict(f.__globals__)
    unknown = set(callees) - set(f.__code__.co_names)
    if unknown:
        raise ValueError(f"{f.__qualname__} does not call {sorted(unknown)}")
    scope.update(callees)
    twin = types.FunctionType(f.__code__, scope, f.__name__, f.__defaults__, f.__closure__)
    twin.__qualname__, twin.__doc__, twin.__module__ = f.__qualname__, f.__doc__, f.__module__
    return numba.njit(inline="always")(twin)
