"""The numba plumbing that the agent (ebrl) and the tasks' kernels (tasks.kernels) share:

- `cache`: numba's on-disk cache keyed on every source file a cached kernel compiles in,
  mended where an entry is damaged; every module that defines a cached kernel imports it;
- `records`: named records for compiled code, numba structrefs defined once, built by name;
- `clip`: `clip_unit`, the one clip of an action to [-1, 1].

It imports no simulator; importing the package itself does nothing.
"""
