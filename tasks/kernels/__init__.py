"""The tasks' per-step work as compiled kernels, around MuJoCo's own C calls.

The mirror of ebrl/kernels.py for the simulator side, one module per job:

| module | what |
|---|---|
| `bindings` | MuJoCo's C functions, its struct fields' views, its stage timers, `run`, the statuses |
| `sensing` | the read-outs: pose, rangefinder distances and Section 3.2's code, velocity |
| `stream` | the task's random stream (numpy's legacy draws, buffered) |
| `body` | what every realisation's record holds and the kernels all share (goal, codes, noise) |
| `two_wheel` | the two-wheel action family's step, written once, on a realisation's phases |
| `servos`, `wheels`, `wheel_motors`, `joint_motors`, `gait` | the family's realisations |
| `plan` | the target plan and its controller (wheel_motors', joint_motors') |
| `thrusters` | the floating drive's realisation and step |
| `env_step` | the entry points `step` (an agent step) and `observe`; a realisation's kernels by its row |

Each realisation's record is a compiled.records.Record of named fields (`<Name>Record` in
the module of its name, named by its row of tasks.realisations.REALISATIONS);
tasks.navigation.Physics builds it. The
dm_env hooks (tasks.navigation.Navigation) run the same `env_step.step`, so each
realisation's logic exists once. Every kernel is ``@njit(cache=True)`` with no fastmath:
the same operations in the same order as the Python they replaced, so the same bits
(tests/data/planar_traces_v*.npz, tests/test_kernels.py).

The kernels live here rather than beside each realisation's Python
(tasks.realisations) because `env_step` compiles every realisation's kernels in, and the
tasks' Python imports `env_step`: kernels under the realisations' package would make an
import circle. This package's __init__ imports nothing.
"""
