"""The readings' registry (ebrl/readings.py, tasks/readings.py): one home per reading.

The configs, `--set` and the studies read it; docs/interpretation.md's table "Every
reading" is checked against it here. The matching rule: the table is the one under the
heading "## Every reading"; each row names its reading in backticks in its first cell;
every registered reading has exactly one row, every row names a registered reading, in
the registry's order (the agent's, then the task's), and each row's other cells are the
registry's own (scope, values with the default, the paper's words, the description), so
the page cannot drift from the code. On a mismatch the message holds the table to paste.
"""
import dataclasses
import pathlib

import pytest

import ebrl
from ebrl import readings as agent_registry
from ebrl.baselines import AGENTS
from experiments.studies import ablation, first_trials, fit
from tasks.config import TaskConfig
from tasks import readings as registry

ROOT = pathlib.Path(__file__).resolve().parents[1]
HEADING = "## Every reading"


def scope(r):
    where = [", ".join(r.drives)] if r.drives else []
    where += [f"{', '.join(r.behaviours)} fallback"] if r.behaviours else []
    where += [f"{', '.join(r.conditions)} condition"] if r.conditions else []
    kind = r.scope + (" (the fallback's)" if r.fallback else "")
    return kind + (": " + "; ".join(where) if where else "")


def values(r):
    default = "None" if r.default is None else f"{r.default:g}" if isinstance(r.default, float) \
        else r.default
    return f"{r.allowed()}; default {default}"


def row(r):
    return f"| `{r.name}` | {scope(r)} | {values(r)} | {r.paper} | {r.what} |"


def table():
    return "\n".join(["| Reading | Scope | Values; default | The paper | What |",
                      "|---|---|---|---|---|"] + [row(r) for r in registry.EVERY])


def doc_rows():
    """The rows of docs/interpretation.md's "Every reading" table, as lines."""
    lines = (ROOT / "docs" / "interpretation.md").read_text().splitlines()
    assert lines.count(HEADING) == 1, f"docs/interpretation.md needs one '{HEADING}' section"
    i = lines.index(HEADING) + 1
    while not lines[i].startswith("|"):
        i += 1
    rows = []
    while i < len(lines) and lines[i].startswith("|"):
        rows.append(lines[i])
        i += 1
    return rows[2:]  # past the header and its rule


def test_the_docs_table_has_one_row_per_registered_reading():
    rows = doc_rows()
    named = [r.split("|")[1].strip().strip("`") for r in rows]
    missing = [r.name for r in registry.EVERY if r.name not in named]
    unknown = [n for n in named if n not in registry.READING_BY_NAME]
    twice = sorted({n for n in named if named.count(n) > 1})
    hint = f"\ndocs/interpretation.md's table should read:\n{table()}"
    assert not missing, f"no row for {missing}{hint}"
    assert not unknown, f"rows name unregistered readings {unknown}{hint}"
    assert not twice, f"more than one row for {twice}{hint}"
    assert rows == [row(r) for r in registry.EVERY], f"rows differ from the registry{hint}"


def test_every_config_reading_field_takes_its_default_from_the_registry():
    for config, readings in ((ebrl.Config, agent_registry.AGENT), (TaskConfig, registry.TASK)):
        fields = {f.name: f for f in dataclasses.fields(config)}
        for r in readings:
            assert r.name in fields, (config, r.name)
            assert fields[r.name].default == r.default or \
                (r.default is None and fields[r.name].default is None), r.name
            assert fields[r.name].type is (str if r.switch else float), r.name
    assert not set(agent_registry.AGENT_BY_NAME) & {f.name for f in dataclasses.fields(TaskConfig)}
    assert list(registry.READING_BY_NAME) == [r.name for r in registry.EVERY]  # no name twice


def test_the_configs_views_are_the_registrys_values_in_order():
    from ebrl import config
    assert config.READINGS == {r.name: r.values for r in agent_registry.AGENT if r.switch}
    assert config.FALLBACK_READINGS == ("eq9_dead_zone", "random_in_avoidance", "random_demand")
    # the kernels' switch constants are the registry's codes, whatever its order
    from tasks.kernels import thrusters, two_wheel
    assert thrusters.THRUST_CLIPPED == registry.READING_BY_NAME["thrust"].values.index("clipped")
    assert thrusters.BUMP_BOUNCE == registry.READING_BY_NAME["bump"].values.index("bounce")
    assert two_wheel.BLOCKED_REFUSE == registry.READING_BY_NAME["blocked_move"].values.index("refuse")
    assert two_wheel.LEFTOVER_AWAY == registry.READING_BY_NAME["leftover_turn"].values.index("away")
    assert registry.codes("bump", "slide", "grip") == (2, 1)
    with pytest.raises(ValueError):
        registry.codes("bump", "sideways")
    for r in registry.EVERY:
        if r.switch:
            assert [r.code(v) for v in r.values] == list(range(len(r.values)))


@pytest.mark.parametrize("name", ["qtable", "mfec"])
def test_every_learner_carries_the_fallbacks_readings_with_their_defaults(name):
    config = AGENTS[name].config()
    for r in agent_registry.AGENT:
        if r.fallback:
            assert getattr(config, r.name) == r.default
    with pytest.raises(ValueError, match="eq9_dead_zone must be one of keep, zero"):
        AGENTS[name].config(eq9_dead_zone="sideways")


@pytest.mark.parametrize("reading", registry.EVERY, ids=lambda r: r.name)
def test_each_reading_takes_its_values_and_refuses_others_in_one_line(reading):
    config = ebrl.Config if reading.scope == "agent" else TaskConfig
    allowed = reading.values if reading.switch else \
        [v for v in (reading.values.low, reading.values.high, 0.5) if v is not None and
         reading.values.problem(v) is None]
    for v in allowed:
        assert getattr(config(**{reading.name: v}), reading.name) == v
    bad = ["sideways", None, 3] if reading.switch else \
        ["0.5", float("nan"), True] + [v for v in (-1e9, 1e9) if reading.values.problem(v)]
    for v in bad:
        with pytest.raises(ValueError) as err:
            config(**{reading.name: v})
        message = str(err.value)
        assert "\n" not in message and message.startswith(reading.name) and repr(v) in message


def test_the_studies_take_values_scope_and_descriptions_from_the_registry():
    for a in ablation.READINGS:
        r = registry.READING_BY_NAME[a.name]
        assert a.what == r.what
        assert a.values == r.values if r.switch else all(r.values.problem(v) is None
                                                         for v in a.values)
    spaces = list(fit.SPACE) + [p for s in first_trials.SPACES.values() for p in s]
    for p in spaces:
        r = registry.READING_BY_NAME[p.name]
        assert p.what == r.what
        if r.switch:
            assert p.kind == "choice" and p.values == r.values
        else:  # a study's search bounds lie inside the reading's allowed values
            assert p.kind == "float" and all(r.values.problem(v) is None for v in p.values)
    # the first trial's space is the drive's: no reading of another drive's
    from tasks.robots import ROBOTS
    for drive, params in first_trials.SPACES.items():
        robot = ROBOTS[first_trials.ROBOTS[drive]]
        assert all(registry.applies(registry.READING_BY_NAME[p.name], robot) for p in params)


def test_applies_follows_the_drive_the_fallback_and_the_condition():
    from tasks.robots import ROBOTS
    two, floating = ROBOTS["two_wheel"], ROBOTS["floating"]
    by = registry.READING_BY_NAME
    assert registry.applies(by["bump"], floating) and not registry.applies(by["bump"], two)
    assert registry.applies(by["blocked_move"], two)
    assert not registry.applies(by["blocked_move"], floating)
    assert registry.applies(by["eq9_dead_zone"], floating, "avoidance")
    assert not registry.applies(by["eq9_dead_zone"], floating, "random")
    assert not registry.applies(by["eq9_dead_zone"], two, "avoidance")
    assert registry.applies(by["episode"], two, "random")
    assert registry.applies(by["radius"], two) and registry.applies(by["radius"], floating)


def test_a_bad_record_is_refused():
    with pytest.raises(ValueError, match="first value"):
        agent_registry.Reading("x", "agent", ("a", "b"), "b", "what")
    with pytest.raises(ValueError, match="scope"):
        agent_registry.Reading("x", "robot", ("a",), "a", "what")
    with pytest.raises(ValueError, match="x must be at most 1"):
        agent_registry.Reading("x", "task", agent_registry.Range(float, 0.0, 1.0), 2.0, "what")


def test_every_robots_own_readings_are_registered_and_allowed():
    from tasks.robots import MOUNTS, ROBOTS, resolve
    for robot in list(ROBOTS.values()) + [resolve(m) for m in MOUNTS]:
        for name, value in robot.readings:
            assert name in registry.READING_BY_NAME, (robot.name, name)
            assert registry.READING_BY_NAME[name].check(value) == value
