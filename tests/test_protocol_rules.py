"""The adopted protocol's rules (issue 48, kept by protocol 8, issue 56), read from the run
records the protocol writes, not from prose: every random action Section 3.4's Gaussian
(mean 0, sd 0.5) for both robots; one learner and one fallback: every agent reading the
same for both robots but Table 1's memory size and eq 9's dead zone (the floating robot's
own equation); and Section 3.3's blocked move, stated: no protocol refuses a move."""
import json

import pytest

import helpers
from experiments.running import execution
from tasks.protocols import PROTOCOL_VERSION
from tasks.robots import PAPER_ROBOTS, ROBOTS

#: The agent fields that may differ between the two robots: Table 1's memory size (its one
#: per-robot value) and eq 9's dead zone (eq 9 is the floating robot's fallback alone).
PER_ROBOT = {"memory_size", "eq9_dead_zone"}
#: Table 1, shared by both robots.
TABLE1 = {"recall_size": 7, "alpha": 0.5, "exploration_rate": 0.05, "discount": 0.99,
          "time_discount": 0.99, "reliability_rate": 0.5}


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    out = tmp_path_factory.mktemp("p7") / "results"
    helpers.ebrl_here("run", "--robot", "paper", "--condition", "all", "--seeds", "0",
                      "--steps", "50", "--workers", "1", "--no-progress", "--out", out, check=True)
    return {(p.parts[-4], p.parts[-3]): json.loads(p.read_text())["parameters"]
            for p in out.glob("*/*/seed_*/run.json")}


def test_every_random_action_is_section_3_4s_gaussian(records):
    assert len(records) == 4
    for (robot, condition), p in records.items():
        assert p["protocol_version"] == PROTOCOL_VERSION == 8
        agent = p["agent"]
        assert agent["random_demand"] == "gaussian", (robot, condition)
        assert agent["random_sd"] == 0.5 and agent["intrinsic_random_rate"] == 0.2


def test_one_learner_and_one_fallback_for_both_robots(records):
    for condition in ("random", "avoidance"):
        tw, fl = (records[(r, condition)]["agent"] for r in PAPER_ROBOTS)
        assert set(tw) == set(fl)
        differ = {k for k in tw if tw[k] != fl[k]}
        assert differ <= PER_ROBOT, differ
        assert (tw["memory_size"], fl["memory_size"]) == (1024, 4096)  # Table 1
        assert {k: tw[k] for k in TABLE1} == TABLE1 == {k: fl[k] for k in TABLE1}
        assert tw["random_in_avoidance"] == fl["random_in_avoidance"]
        assert tw["policy_threshold"] == fl["policy_threshold"]


def test_no_protocol_refuses_a_blocked_move(records):
    """Section 3.3 states the blocked move (moved to the touch, the rest turned): every run
    records blocked_move "stop", and every protocol gives it to every robot."""
    from tasks.protocols import PROTOCOLS
    for (robot, condition), p in records.items():
        if robot == "two_wheel":
            assert p["task"]["blocked_move"] == "stop", (robot, condition)
    for protocol in PROTOCOLS.values():
        for name, entry in ROBOTS.items():
            readings = dict(protocol.readings_for(name, entry.drive))
            assert readings.get("blocked_move", "stop") == "stop", (protocol.name, name)


def test_every_registered_robot_has_the_one_learner():
    """Every registered robot's agent config (the 3D robots inherit their drive's) agrees
    with the two-wheel robot's but for the per-robot fields."""
    import dataclasses
    base = dataclasses.asdict(execution.RunSpec("two_wheel", "avoidance", 0, 10).agent_config())
    for name in ROBOTS:
        mine = dataclasses.asdict(execution.RunSpec(name, "avoidance", 0, 10).agent_config())
        assert {k for k in base if base[k] != mine[k]} <= PER_ROBOT, name
        assert mine["random_demand"] == "gaussian"


def test_one_default_per_reading_the_literal_protocols_and_paper_config_is_that_learner():
    """A reading's registry default is the literal protocol's value (the paper as
    written), so ebrl.paper_config, Table 1 and the defaults, builds the literal
    protocol's learner for each paper robot, and ebrl.Config() column T's."""
    import dataclasses

    import ebrl
    from tasks import readings as registry
    from tasks.protocols import LITERAL
    literal = dict(LITERAL.readings)
    assert {r.name: r.default for r in registry.EVERY} == literal
    for robot in PAPER_ROBOTS:
        entry = ROBOTS[robot]
        built = dataclasses.asdict(execution.RunSpec(robot, "avoidance", 0, 10,
                                                     protocol="literal").agent_config())
        assert dataclasses.asdict(ebrl.paper_config(entry.table1)) == built, robot
    assert ebrl.Config() == ebrl.paper_config("T")
