"""What the local pool's server process (pool.context) does once, before it forks each
worker: imports the modules a run loads (the worker, the loop, the simulator, the tasks'
kernels, the agent) and starts numba's CPU target by loading one small kernel from the
cache. The first compiled call in a process costs about 0.6 s of CPU (numba builds its
typing and lowering registries, SciPy's BLAS check among them); a worker forked from the
server starts with it done, where each worker paid it at its first run (docs/speed.md,
"The test suite's time")."""
import numpy as np

import ebrl.agent  # noqa: F401  imported for the workers
import tasks.environment
import tasks.kernels.env_step  # noqa: F401
from compiled.clip import clip_unit
from experiments.running import fused, worker  # noqa: F401

clip_unit(np.zeros(1))
