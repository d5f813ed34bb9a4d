"""The one clip of an action to [-1, 1], for the agent's random action and fallbacks
(ebrl.intrinsic, ebrl.steps) and the tasks' checked action (tasks.kernels.body)."""
from numba import njit

from compiled import cache  # noqa: F401  numba's cache keyed on every file a kernel compiles in


@njit(cache=True)
def clip_unit(a):
    """a clipped to [-1, 1] in place, as np.clip (Section 3.4's random action is clipped;
    ebrl.intrinsic's fallbacks use it too)."""
    for i in range(a.shape[0]):
        v = a[i]
        v = v if v > -1.0 else -1.0
        a[i] = v if v < 1.0 else 1.0
    return a
