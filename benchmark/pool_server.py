"""What the local pool's fork server does before it forks any worker (:func:`benchmark.parallel.pool_context`).

The server imports this module first. It limits the process's native thread pools to one thread
each (:data:`benchmark.parallel.ONE_CORE_ENV`, before NumPy's OpenBLAS, OpenMP, numba or Mesa's
llvmpipe loads: they read it once, when they load) and sets the command's garbage collector
(:mod:`benchmark.collector`), then makes numba's CPU target ready, which each worker would otherwise
do at its first compiled call (0.15-0.2 s of CPU, measured). Nothing else imports it.
"""

from benchmark import collector
from benchmark.parallel import one_core_worker

one_core_worker()
collector.tune()  # the forked workers inherit it

from numba.core.registry import cpu_target  # noqa: E402  (after the environment above)

cpu_target.target_context.refresh()
