"""The task's random stream as compiled code draws it.

dm_control's tasks draw from a legacy RandomState (MT19937), which numba cannot take.
Its draws are doubles from one stream (random_sample; the legacy normal's polar method
takes its pairs from the same doubles), so the task's draws come from a buffer of the
stream's next doubles (`Stream`), used by the legacy algorithms (`gauss`, numpy's
legacy_gauss); the RandomState is wound to just past what was used whenever Python reads
it (`TaskStream`). tests/test_kernels.py checks the draws against numpy's own.
"""
import math

import numpy as np
from numba import njit

from compiled import cache  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from compiled import records


#: A buffer's doubles; a step uses about a dozen.
BUFFER = 8192
#: Draws stop before a step when fewer doubles than this are left (a step's draws: 2
#: uniforms and 2 per attempt of each pair of normals, whose attempts repeat with
#: probability 1 - pi / 4).
RESERVE = 64


@records.record("buffer", "cursor", "has_gauss", "gauss")
class Stream(records.Record):
    """A stretch of the task's RandomState as doubles: the buffer, the next double's
    index, and legacy_gauss's cached value (has_gauss, gauss)."""


Stream.constructor = njit(cache=True)(lambda *values: Stream(*values))


@njit(cache=True)
def stream_state(st):
    """(cursor, has_gauss, gauss) of a Stream, for Python."""
    return st.cursor, st.has_gauss, st.gauss


@njit(cache=True)
def stream_refill(st, buffer, has_gauss, value):
    """The Stream starts over on `buffer` with legacy_gauss's cache (has_gauss, value)."""
    st.buffer = buffer
    st.cursor = 0
    st.has_gauss = has_gauss
    st.gauss = value


@njit(cache=True)
def gauss(st):
    """numpy's legacy_gauss on the buffered doubles: the cached value if there is one,
    else the polar method on pairs of doubles, keeping the second value."""
    if st.has_gauss:
        value = st.gauss
        st.has_gauss = 0
        st.gauss = 0.0
        return value
    buf = st.buffer
    while True:
        p = st.cursor
        x1 = 2.0 * buf[p] - 1.0
        x2 = 2.0 * buf[p + 1] - 1.0
        st.cursor = p + 2
        r2 = x1 * x1 + x2 * x2
        if not (r2 >= 1.0 or r2 == 0.0):
            break
    f = math.sqrt(-2.0 * math.log(r2) / r2)
    st.gauss = f * x1
    st.has_gauss = 1
    return f * x2


@njit(cache=True)
def task_draws(st, u, z, sensor_noise, vz, velocity_noise):
    """One step's draws of the task, in its order: the action noise's two uniforms (u),
    the sensor noise's normals (z: RandomState.normal(0, sd, size)), the floating
    velocity noise's normals (vz); an array is empty where its noise is off. Returns
    False, with the stream as it was, when the buffer might run out meanwhile."""
    start, had, value = st.cursor, st.has_gauss, st.gauss
    if start + u.shape[0] + 4 * (z.shape[0] + vz.shape[0]) + RESERVE > st.buffer.shape[0]:
        return False
    for i in range(u.shape[0]):
        u[i] = st.buffer[st.cursor]
        st.cursor += 1
    for i in range(z.shape[0]):
        z[i] = 0.0 + sensor_noise * gauss(st)
    for i in range(vz.shape[0]):
        vz[i] = 0.0 + velocity_noise * gauss(st)
    if st.cursor > st.buffer.shape[0] - RESERVE:  # pragma: no cover - many rejections in a row
        st.cursor, st.has_gauss, st.gauss = start, had, value
        return False
    return True


class TaskStream:
    """The task's RandomState as the compiled draws read it (Stream, in `record`): `fill`
    saves the RandomState's state and draws a buffer of its next doubles; `settle` winds
    it to just past the doubles the draws used, with legacy_gauss's cached value as they
    left it. While a buffer is out, the RandomState itself is ahead of what was used:
    `settled()` is the way to it."""

    def __init__(self, random):
        self._random = random
        self.record = Stream.build(buffer=np.zeros(0), cursor=0, has_gauss=0, gauss=0.0)
        self._saved = None

    def fill(self):
        """A fresh buffer of the stream's next doubles (after settling the last)."""
        self.settle()
        self._saved = state = self._random.get_state()
        stream_refill(self.record, self._random.random_sample(BUFFER),
                              int(state[3]), float(state[4]))

    def settle(self):
        """The RandomState wound to just past the doubles used; the buffer is dropped."""
        if self._saved is None:
            return
        cursor, has_gauss, value = stream_state(self.record)
        self._random.set_state(self._saved)
        if cursor:
            self._random.random_sample(int(cursor))
        state = self._random.get_state()
        self._random.set_state(state[:3] + (int(has_gauss), float(value)))
        self._saved = None

    def ready(self):
        """A buffer out (a fresh one unless one is)."""
        if self._saved is None:
            self.fill()

    def settled(self):
        """The RandomState, settled."""
        self.settle()
        return self._random

    def draws(self, u, z, sensor_noise, vz, velocity_noise):
        """One step's draws into u, z, vz (task_draws), from a new buffer
        where the current one might run out."""
        if self._saved is None or not task_draws(self.record, u, z, sensor_noise, vz,
                                                         velocity_noise):
            self.fill()
            task_draws(self.record, u, z, sensor_noise, vz, velocity_noise)
