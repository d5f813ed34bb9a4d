"""The settings a run can change (`--set NAME=VALUE`): every learner's config fields, then
the task's, each with the kind of value it takes and its default, the robots' own where
their registry entries give one; a setting that is a reading of the paper takes its kind
and allowed values from the readings' registry (tasks.readings). What a setting is, not
how the command line parses it (experiments.checks.validate does that). Imports nothing
heavy.
"""
import dataclasses

from experiments.running.learners import LEARNERS
from tasks.config import TaskConfig
from tasks.readings import READING_BY_NAME


def _classes():
    """The config classes whose fields --set may name: every learner's, then the task's."""
    return [learner.config for learner in LEARNERS.values()] + [TaskConfig]


def kinds():
    """Every --set name, the learners' (ebrl.Config, the baselines') then the task's
    (tasks.TaskConfig), with the type its value takes (a reading's from its registry
    entry, else its default's)."""
    found = {}
    for cls in _classes():
        default = cls()
        for f in dataclasses.fields(cls):
            reading = READING_BY_NAME.get(f.name)
            found[f.name] = reading.type if reading else type(getattr(default, f.name))
    return found


def check(name, value):
    """value for the setting name, or ValueError in one line where name is a reading of
    the paper and value not among its allowed values (tasks.readings; the configs check
    the rest, experiments.checks.validate.agent_configs)."""
    return READING_BY_NAME[name].check(value) if name in READING_BY_NAME else value


def default(name, entries=()):
    """The default value of a --set name (EBRL's, a baseline's, or the task's); with
    robots' registry entries, theirs (their readings: tasks.robots.Robot): one
    value if they agree, else None."""
    if entries:
        values = {dict(e.readings).get(name, default(name)) for e in entries}
        return values.pop() if len(values) == 1 else None
    for cls in _classes():
        if hasattr(cls(), name):
            return getattr(cls(), name)
    raise ValueError(f"unknown setting {name!r}")
