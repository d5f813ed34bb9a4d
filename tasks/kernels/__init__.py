"""The tasks' per-step work as compiled kernels, around MuJoCo's own C calls.

The mirror of ebrl/kernels.py for the simulator side, one module per job:

| module | what |
|---|---|
| `bindings` | MuJoCo's C functions, its struct fields' views, its stage timers, `run`, the statuses |
| `sensing` | the read-outs: pose, rangefinder distances and Section 3.2's code, velocity |
| `stream` | the task's random stream (numpy's legacy draws, buffered) |
| `body` | what every drive's record holds and the kernels every drive shares (goal, codes, noise) |
| `two_wheel` | the two-wheel action family's step, written once |
| `planar`, `wheels`, `motors`, `gait`, `joints` | the family's realisations: how a body turns and moves |
| `floating` | the floating drive's step |
| `steps` | the entry points: a whole agent step (`step`), a drive's action (`act`) |

Each drive's record is an ebrl.records.Record of named fields; tasks.navigation.Physics
builds it. The dm_env hooks (tasks.navigation.Navigation) call these same kernels, so
each drive's logic exists once. Every kernel is ``@njit(cache=True)`` with no fastmath:
the same operations in the same order as the Python they replaced, so the same bits
(tests/data/planar_traces_v*.npz, tests/test_kernels.py).

The kernels live here rather than beside each drive's Python (tasks.two_wheel,
tasks.floating, tasks.gait) because `steps` compiles every drive's kernels in, and the
drives' Python imports `steps`: kernels under the drives' packages would make an import
circle. This package's __init__ imports nothing.
"""
