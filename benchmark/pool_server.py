"""What the local pool's fork server does before it imports the job's module (:func:`benchmark.parallel.pool_context`).

The server imports this module first. It limits the process's native thread pools to one thread
each (:data:`benchmark.parallel.ONE_CORE_ENV`, before NumPy's OpenBLAS, OpenMP, numba or Mesa's
llvmpipe loads: they read it once, when they load) and sets the command's garbage collector
(:mod:`benchmark.collector`). After the job's module, the server imports :mod:`benchmark.pool_ready`.
Nothing else imports it.
"""

from benchmark import collector
from benchmark.parallel import one_core_worker

one_core_worker()
collector.tune()  # the forked workers inherit it
