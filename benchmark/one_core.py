"""Importing this module limits the process's native thread pools to one thread each.

The local pool's fork server imports it first (:data:`benchmark.parallel.SERVER_SETUP`), so that
NumPy's OpenBLAS, OpenMP, numba and Mesa's llvmpipe, loaded after it there, start one thread each
in every worker forked from the server (:data:`benchmark.parallel.ONE_CORE_ENV`). Nothing else
imports it.
"""

from benchmark.parallel import one_core_worker

one_core_worker()
