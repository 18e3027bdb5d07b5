"""What the local pool's fork server does last, after it has imported the job's module
(:func:`benchmark.parallel.pool_context`).

Where that module uses numba (it is loaded now), the server makes numba's CPU target ready, which
each forked worker would otherwise do at its first compiled call (0.15-0.2 s of CPU a worker,
measured). A job that does not use numba (the module of ``__main__``, which the server does not
import, or a module without kernels) leaves numba unloaded: importing and readying it would cost
its server about 0.5 s of CPU for nothing. Nothing else imports this module.
"""

import sys

if "numba" in sys.modules:
    from numba.core.registry import cpu_target

    cpu_target.target_context.refresh()
