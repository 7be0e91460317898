"""One BLAS thread for the path's vector algebra, so that its numbers do not depend on the machine.

NumPy's BLAS (OpenBLAS) splits a long dot product or norm over its threads and adds the parts in an order that
depends on how many there are: on a 420,000-long vector, 1 and 2 threads differ by 3.5e-12 of 360. A path through
a creasing notch amplifies such last digits into where it ends (6 x 8 mm's path mesh ended 15 mrad apart). A
sweep's workers already run on one thread each; `one_blas_thread` gives any caller the same digits. MKL's PARDISO
is left as it is: in its reproducible mode (`fea.pardiso`) its solutions are the same on 1 and 2 threads.
"""

from __future__ import annotations

import functools
from typing import Callable, TypeVar

from threadpoolctl import ThreadpoolController

F = TypeVar("F", bound=Callable)


@functools.cache
def _openblas():
    return ThreadpoolController().select(internal_api="openblas")


def one_blas_thread(function: F) -> F:
    """`function` run with OpenBLAS on one thread (the caller's setting restored after)."""
    @functools.wraps(function)
    def wrapper(*args, **kwargs):
        with _openblas().limit(limits=1):
            return function(*args, **kwargs)
    return wrapper  # type: ignore[return-value]
