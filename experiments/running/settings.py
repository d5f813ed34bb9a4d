"""The settings a run can change (`--set NAME=VALUE`): every learner's config fields, then
the task's, each with the kind of value it takes and its default, the robots' own where
their registry entries give one. What a setting is, not how the command line checks it
(experiments.checks.validate does that). Imports nothing heavy until asked.
"""


def _classes():
    """The config classes whose fields --set may name: every learner's, then the task's."""
    from experiments.running import protocol
    from tasks.config import TaskConfig
    return [protocol.agent_classes(a)[0] for a in protocol.AGENTS] + [TaskConfig]


def kinds():
    """Every --set name, the learners' (ebrl.Config, the baselines') then the task's
    (tasks.TaskConfig), with the type its value takes (a field whose default is None
    takes a number)."""
    import dataclasses
    found = {}
    for cls in _classes():
        default = cls()
        for f in dataclasses.fields(cls):
            value = getattr(default, f.name)
            found[f.name] = float if value is None else type(value)
    return found


def default(name, entries=()):
    """The default value of a --set name (EBRL's, a baseline's, or the task's); with
    robots' registry entries, theirs (their readings, tasks.robots.Drive.readings): one
    value if they agree, else None."""
    if entries:
        values = {dict(e.readings).get(name, default(name)) for e in entries}
        return values.pop() if len(values) == 1 else None
    for cls in _classes():
        if hasattr(cls(), name):
            return getattr(cls(), name)
    raise ValueError(f"unknown setting {name!r}")
