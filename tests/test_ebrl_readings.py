"""The readings that are switches (ebrl.config.READINGS): the defaults reproduce the
agent as it was before the switches bit for bit, and each alternative changes exactly
what it names, on a case computed by hand."""
import hashlib

import numpy as np
import pytest

import ebrl
from ebrl import intrinsic, kernels
from ebrl.config import READINGS

from test_ebrl_memory import chains_are_consistent

# -- the defaults, bit for bit ----------------------------------------------------------

STREAMS = {  # name: (obs_dim, intrinsic behaviour, groups, group weights, memory size)
    "one_group": (7, "eq8", None, None, 64),
    "groups_8_2": (10, "eq9-10", [np.arange(8), np.arange(8, 10)], [0.7, 0.3], 128),
}

#: sha256 of the actions rounded to 1e-9, and of the final utility, reliability, time,
#: next and prev arrays, of stream(name) with protocol 3's Config. The state digests were
#: computed BEFORE the switches were written, on the unmodified code of commit e425110;
#: the actions' digest was exact there too, but the actions' last bits differ between
#: machines (numpy's BLAS and math kernels per CPU), so they are compared rounded, from
#: commit d5bc6e0 (which matched e425110's exact digests) run on a machine of today's kind.
#: tests/data/make_golden.py computes them again (--check compares).
BEFORE = {
    "one_group": ("68c03ebd04a2301c67fa9be9dfb9fc8c089d73a68a92a50553593f4aa00d106f",
                  "f1d92c4eef6e1e9b7ef9ed16943177dbbbf753b15cb8d8e6d63863e3fdfdf5cc"),
    "groups_8_2": ("9aa8f32f9cd5d16ab4d9ef59ac8556c7bb06571ff14a772a2e8c8b72ffc3a8ec",
                   "53e0f7fb9bce76a3d29b71af2efe49930ba4d7d7d31db080054d3ae1eadb5f6c"),
}

DEFAULTS = {name: values[0] for name, values in READINGS.items()}
#: The readings BEFORE was computed with (today's defaults, spelled out, so that a change
#: of a default leaves BEFORE's meaning and these tests as they are).
PROTOCOL3 = {"eq9_dead_zone": "zero", "initial_reliability": 1.0}
FALLBACK_SWITCHES = ("eq9_dead_zone", "random_in_avoidance", "random_demand")


def stream(name, steps=3000, explicit=False, **switches):
    """The agent with the avoidance fallback on a fixed random input stream: trials
    ending at random (reward 1), a reward of -0.1 on 2% of the other steps, a memory
    small enough to forget. explicit=True spells every switch out (the defaults, or
    `switches`) in the Config and in fallback_for; otherwise fallback_for gets its
    positional arguments only unless a fallback switch is given."""
    obs_dim, behaviour, groups, weights, memory = STREAMS[name]
    if explicit:
        switches = {**DEFAULTS, "initial_reliability": ebrl.Config().initial_reliability,
                    **switches}
    cfg = ebrl.Config(memory_size=memory, **switches)
    fb_switches = {k: getattr(cfg, k) for k in FALLBACK_SWITCHES
                   if explicit or k in switches}
    fb = intrinsic.fallback_for(behaviour, "avoidance", cfg.intrinsic_random_rate,
                                cfg.random_sd, **fb_switches)
    ag = ebrl.Agent(cfg, obs_dim, fb.action_dim, fb, groups=groups, group_weights=weights,
                    seed=11)
    rng = np.random.default_rng(2024)
    actions = np.empty((steps, fb.action_dim))
    for t in range(steps):
        obs = rng.random(obs_dim)
        actions[t] = ag.act(obs, ranges=obs[:8] if obs_dim == 10 else obs)
        last = rng.random() < 1 / 60
        reward = 1.0 if last else (-0.1 if rng.random() < 0.02 else 0.0)
        ag.learn(reward, last)
    return actions, ag


STATE = ("utility", "rel", "time", "nxt", "prev")


def digests(actions, ag):
    state = b"".join(np.ascontiguousarray(getattr(ag.memory, k)).tobytes() for k in STATE)
    return (hashlib.sha256(np.round(actions, 9).tobytes()).hexdigest(),
            hashlib.sha256(state).hexdigest())


@pytest.mark.parametrize("name", STREAMS)
def test_protocol_3_readings_reproduce_the_agent_before_the_switches(name):
    """The agent with protocol 3's readings (the defaults) against BEFORE, the digests of the agent
    before the switches (computed on commit e425110's unmodified code: actions, and
    final utilities, reliabilities, time stamps, links), and against an agent whose
    Config and fallback spell every switch out."""
    actions, ag = stream(name, **PROTOCOL3)
    assert ag.size == STREAMS[name][4] and ag.memory_decisions > 1000
    assert ag.fallback_decisions > 500
    assert digests(actions, ag) == BEFORE[name]
    actions2, ag2 = stream(name, explicit=True, **PROTOCOL3)
    assert np.array_equal(actions, actions2)
    for k in STATE + ("inputs", "actions", "table", "table_w", "variance"):
        assert np.array_equal(getattr(ag.memory, k), getattr(ag2.memory, k)), k


@pytest.mark.parametrize("name", STREAMS)
@pytest.mark.parametrize("field,value", [(f, v) for f, vs in READINGS.items() for v in vs
                                          if v != PROTOCOL3.get(f, vs[0])]
                         + [("initial_reliability", 0.5), ("initial_reliability", 0.0)])
def test_each_alternative_changes_the_run_and_keeps_the_memory_consistent(name, field, value):
    actions, ag = stream(name, **{**PROTOCOL3, field: value})
    chains_are_consistent(ag)
    assert ag.size == STREAMS[name][4]
    assert np.isfinite(ag.reliability).all() and (ag.reliability >= 0).all()
    assert (ag.reliability <= 1).all()
    changed = digests(actions, ag) != BEFORE[name]
    # eq 8 (the one-group stream's behaviour) has no dead zone; the stream's fallback is
    # the avoidance condition's, whose random action "uniform_walk" leaves Gaussian; eq 7's
    # walk stopped at eq 6's cutoff (about 917 steps back) cannot stop within the stream's
    # trials of about 60 steps (test_eq7_walks_by_hand has its case).
    assert changed == (not (field == "eq9_dead_zone" and name == "one_group")
                       and value != "uniform_walk" and (field, value) != ("eq7_walk", "cut"))


# -- validation ------------------------------------------------------------------------

@pytest.mark.parametrize("field", READINGS)
def test_unknown_reading_names_the_field_and_the_values(field):
    with pytest.raises(ValueError) as err:
        ebrl.Config(**{field: "sideways"})
    message = str(err.value)
    assert "\n" not in message and field in message and "sideways" in message
    assert all(v in message for v in READINGS[field])
    with pytest.raises(ValueError, match=field):
        ebrl.Config(**{field: None})
    if field in FALLBACK_SWITCHES:
        with pytest.raises(ValueError, match=field):
            intrinsic.fallback_for("eq9-10", "avoidance", **{field: "sideways"})


def test_switch_values_default_first_and_paper_config_takes_them():
    assert all(getattr(ebrl.Config(), f) == vs[0] for f, vs in READINGS.items())
    c = ebrl.paper_config("F", forgetting="oldest", episode="continuing")
    assert (c.memory_size, c.forgetting, c.episode) == (4096, "oldest", "continuing")


@pytest.mark.parametrize("value", [-0.1, 1.5, float("nan"), "1"])
def test_initial_reliability_is_validated(value):
    with pytest.raises(ValueError, match="initial_reliability"):
        ebrl.Config(initial_reliability=value)


# -- hand-made cases ---------------------------------------------------------------------

def _agent(fallback=None, **kw):
    """The hand-computed cases start a new element at reliability 1 (protocol 3's
    default), so that eq 7's steps are easy to follow; a case may set it."""
    kw = {"exploration_rate": 0.0, "recall_size": 2, "initial_reliability": 1.0, **kw}
    return ebrl.Agent(ebrl.Config(**kw), 1, 1,
                      fallback or (lambda r, rng: np.array([-0.5])), seed=0)


def _step(ag, x, reward=0.0, last=False):
    a = ag.act(np.array([float(x)]))
    ag.learn(reward, last)
    return a


def _kept_times(ag):
    return sorted(ag.memory.time[: ag.size].tolist())


@pytest.mark.parametrize("forgetting,forgotten", [("least_reliable", 1), ("oldest", 0)])
def test_forgetting_least_reliable_or_oldest(forgetting, forgotten):
    """Slot 0 (time 0) is the oldest, but eq 7 has raised its reliability above slot 1's
    (time 1): "least_reliable" forgets slot 1, "oldest" slot 0."""
    ag = _agent(memory_size=3, time_discount=0.5, reliability_rate=0.5, forgetting=forgetting)
    _step(ag, 0)
    _step(ag, 5, 1.0, last=True)  # trial 1: elements 0 (x 0) and 1 (x 5), rewarded
    _step(ag, 0, 1.0, last=True)  # trial 2: memory acts as element 0; eq 7 from it
    assert ag.referred == -1 and ag.memory_decisions == 1
    # R_0 = (0.25 + 0.5 * 0.75) * 0.5, R_1 = 0.5 * 0.5, R_2 = 0.5 (stored at time 2).
    np.testing.assert_array_equal(ag.reliability, [0.3125, 0.25, 0.5])
    _step(ag, 9)  # memory full: one element is forgotten, its slot reused (time 3)
    assert ag.memory.time[forgotten] == 3
    assert _kept_times(ag) == sorted({0, 1, 2, 3} - {forgotten})


def test_oldest_kernel_takes_the_smallest_time_stamp():
    assert kernels.oldest(np.array([5, 3, 9, 3, 4]), 5) == 1
    assert kernels.oldest(np.array([5, 3, 9]), 1) == 0


@pytest.mark.parametrize("initial,kept", [
    # 1: every new element is the most reliable; the reinforced element 0 is still the
    # least reliable at time 3, then element 1: first in, first out.
    (1.0, [2, 3, 4]),
    # 0.5: element 0, reinforced (0.45 -> 0.725), outlives the unreinforced 1, then 2.
    (0.5, [0, 3, 4]),
    # 0: unreinforced elements stay at 0; the first slot of reliability 0 goes: slot 1
    # (time 1), then slot 1 again (time 3, the newest), not slot 2 (time 2).
    (0.0, [0, 2, 4]),
])
def test_initial_reliability_sets_the_forgetting_order(initial, kept):
    """Elements stored at times 0-4 in a memory of 3 with time discount 0.9 and rho 0.5;
    element 0 is reinforced by eq 7 at time 1 (R_0 = 0.9 R0 + 0.5 (1 - 0.9 R0), then
    decays); elements 3 and 4 each need a forgotten slot."""
    ag = _agent(memory_size=3, time_discount=0.9, reliability_rate=0.5,
                initial_reliability=initial)
    _step(ag, 0, 1.0, last=True)   # time 0, element 0
    _step(ag, 0, 1.0, last=True)   # time 1: memory acts as element 0; eq 7 on it
    assert ag.memory_decisions == 1
    r0 = 0.9 * initial
    np.testing.assert_allclose(ag.reliability, [(r0 + 0.5 * (1 - r0)) * 0.9, r0], rtol=1e-15)
    _step(ag, 9)                   # time 2
    _step(ag, 9.5)                 # time 3: forgets one
    _step(ag, 10)                  # time 4: forgets another
    assert ag.memory_decisions == 1  # utilities of 0 elsewhere: the fallback acted
    assert _kept_times(ag) == kept


@pytest.mark.parametrize("episode", ["trial", "continuing"])
def test_episode_continuing_keeps_the_link_across_a_trial_end(episode):
    """Trial 1 (times 0, 1) ends unrewarded, trial 2 (times 2, 3) is rewarded at its
    end. "trial": eq 6 stops at trial 2's first element; "continuing": the link from
    time 1 to time 2 is kept and eq 6 reaches trial 1's elements, gamma^(t - t_j)."""
    ag = _agent(memory_size=8, discount=0.5, utility_cutoff=0.01, episode=episode)
    _step(ag, 0)
    _step(ag, 1, 0.0, last=True)
    _step(ag, 2)
    _step(ag, 3, 1.0, last=True)
    if episode == "trial":
        assert ag.memory.prev[2] == -1 and ag.memory.nxt[1] == -1
        np.testing.assert_array_equal(ag.utility, [0, 0, 0.5, 1])
    else:
        assert ag.memory.prev[2] == 1 and ag.memory.nxt[1] == 2
        np.testing.assert_array_equal(ag.utility, [0.125, 0.25, 0.5, 1])
    assert ag.tail == (-1 if episode == "trial" else 3)
    assert ag.referred == -1 and not ag.recall_table()[0].size  # emptied either way


@pytest.mark.parametrize("episode", ["trial", "continuing"])
def test_episode_continuing_lets_eq7_cross_a_trial_end(episode):
    """eq7_scope "to_start" from an element of trial 2 back to its episode's start:
    with "continuing" that reaches trial 1's element too."""
    ag = _agent(memory_size=8, time_discount=0.5, reliability_rate=0.5, episode=episode)
    _step(ag, 0, 0.0, last=True)   # trial 1: element 0
    _step(ag, 5)                   # trial 2: elements 1, 2; rewarded
    _step(ag, 6, 1.0, last=True)
    before = ag.reliability.copy()  # 0.5^3, 0.5^2, 0.5
    _step(ag, 5, 1.0, last=True)   # memory acts as element 1; eq 7 from it
    assert ag.memory_decisions == 1
    def up(r):  # eq 7 (r = 1), then the decay
        return (r + 0.5 * (1 - r)) * 0.5
    want = [up(before[0]) if episode == "continuing" else before[0] * 0.5,
            up(before[1]), before[2] * 0.5, 0.5]
    np.testing.assert_array_equal(ag.reliability, want)


@pytest.mark.parametrize("recall", ["empty", "keep"])
def test_recall_table_kept_or_emptied_at_a_trial_end(recall):
    """Trial 1 stores x = 0, 5, 0, 5 (elements 0 -> 1 -> 2 -> 3) and ends; trial 2 starts
    with x = 5. "empty": its act starts from an empty table; "keep": from trial 1's last
    table, whose entries advance along their forward links by eq 1 as on any step."""
    ag = _agent(memory_size=8, recall_size=3, recall_at_trial_end=recall)
    for x in (0, 5, 0):
        _step(ag, x)
    ag.act(np.array([5.0]))
    table, weights = ag.memory.table.copy(), ag.memory.table_w.copy()
    assert table[0] == 1 and weights[0] == 1.0  # x = 5 recalls element 1 exactly
    ag.learn(0.0, last=True)
    if recall == "empty":
        assert (ag.memory.table == -1).all()
        table[:] = -1
    else:
        assert ag.memory.table.tolist() == table.tolist() and ag.memory.table_w.tolist() == weights.tolist()
    sim = ag.similarities(np.array([5.0]))  # the next act's similarities
    kernels.recall(sim, ag.size, ag.memory.nxt, table, weights, 0.5)
    ag.act(np.array([5.0]))
    assert ag.memory.table.tolist() == table.tolist() and ag.memory.table_w.tolist() == weights.tolist()
    # By hand: V = var(0, 5, 0, 5) = 6.25, S(5, 0) = 1 - sqrt(25 / 6.25 / 2) = 1 - sqrt 2,
    # S(5, 5) = 1. "keep": the entry on element 1 (W 1) reaches element 2 with eq 1's
    # 1 + 0.5 (1 - sqrt 2 - 1) = 1 - sqrt(2) / 2, above element 2's own similarity.
    # "empty": elements 1 and 3, then the first of 0 and 2 (equal weights).
    if recall == "keep":
        assert ag.memory.table.tolist() == [1, 3, 2]
        np.testing.assert_allclose(ag.memory.table_w, [1, 1, 1 - np.sqrt(2) / 2], rtol=1e-15)
    else:
        assert ag.memory.table.tolist() == [1, 3, 0]
        np.testing.assert_allclose(ag.memory.table_w, [1, 1, 1 - np.sqrt(2)], rtol=1e-15)


@pytest.mark.parametrize("scope", ["to_start", "decided_only"])
def test_eq7_scope_to_start_or_decided_only(scope):
    """Trial 1: elements 0, 1, 2 (x 0, 1, 2), rewarded. Trial 2: memory acts as element
    0, then as element 2, and the reward comes. "to_start" changes 2, 1, 0 (back from
    element 2); "decided_only" changes 0 and 2, once each, and leaves element 1, which
    decided nothing, to the time discount alone."""
    ag = _agent(memory_size=8, time_discount=0.5, reliability_rate=0.5, eq7_scope=scope)
    for x in (0, 1, 2):
        _step(ag, x, 1.0 if x == 2 else 0.0, last=x == 2)
    assert not ag.memory.decided.any()
    _step(ag, 0)
    assert ag.referred == 0
    assert ag.memory.decided[:5].tolist() == ([True, False, False, False, False]
                                        if scope == "decided_only" else [False] * 5)
    before = ag.reliability.copy()
    _step(ag, 2, 1.0, last=True)
    assert ag.memory_decisions == 2
    def up(r):
        return (r + 0.5 * (1 - r)) * 0.5

    def decay(r):
        return r * 0.5
    if scope == "to_start":
        want = [up(before[0]), up(before[1]), up(before[2]), decay(before[3]), 0.5]
    else:
        want = [up(before[0]), decay(before[1]), up(before[2]), decay(before[3]), 0.5]
    np.testing.assert_array_equal(ag.reliability, want)
    assert not ag.memory.decided.any()  # cleared at the trial's end


def test_eq7_decided_only_counts_an_element_once_and_forgets_its_flag():
    rel = np.array([0.5, 0.5, 0.5])
    decided = np.array([True, False, True])
    kernels.eq7_decided(rel, decided, 3, -1.0, 0.5)
    np.testing.assert_array_equal(rel, [0.25, 0.5, 0.25])
    # A flagged element that is forgotten loses its flag with its slot.
    ag = _agent(memory_size=2, time_discount=0.5, eq7_scope="decided_only")
    _step(ag, 0, 1.0, last=True)
    ag.act(np.array([0.0]))  # memory acts as element 0 ...
    assert ag.memory.decided[0]
    ag.learn(0.0)            # ... which is stored into slot 1
    ag.act(np.array([0.0]))  # element 0 again (element 1's utility is 0)
    ag.learn(0.0)            # full: slot 0 (least reliable) is reused
    assert ag.memory.time[0] == 2 and not ag.memory.decided[0]


def test_eq9_dead_zone_keep_repeats_the_previous_acceleration():
    west, north = np.eye(8)[4], np.eye(8)[2]  # E, NE, N, NW, W, SW, S, SE
    quiet = np.full(8, 0.1)                   # b = 0 on both axes: the dead zone
    zero = intrinsic.fallback_for("eq9-10", "avoidance", 0.0, eq9_dead_zone="zero")
    keep = intrinsic.fallback_for("eq9-10", "avoidance", 0.0)  # the default: the literal one
    rng = np.random.default_rng(0)
    # West only: b_h = 0.5 -> 1/3; b_v = 0 (dead zone).
    np.testing.assert_array_equal(zero(west, rng), [1 / 3, 0])
    np.testing.assert_array_equal(keep(west, rng), [1 / 3, 0])
    # North only: b_h = 0 (dead zone: 0, or 1/3 kept), b_v = -0.5 -> -1/3.
    np.testing.assert_array_equal(zero(north, rng), [0, -1 / 3])
    np.testing.assert_array_equal(keep(north, rng), [1 / 3, -1 / 3])
    np.testing.assert_array_equal(zero(quiet, rng), [0, 0])
    np.testing.assert_array_equal(keep(quiet, rng), [1 / 3, -1 / 3])
    keep.reset()  # a trial's end: at rest again
    np.testing.assert_array_equal(keep(quiet, rng), [0, 0])
    # The previous action is the fallback's, random ones included.
    keep.random_rate = 1.0
    kicked = keep(quiet, rng)
    keep.random_rate = 0.0
    np.testing.assert_array_equal(keep(quiet, rng), kicked)
    # The pure function: `previous` fills the dead zone only.
    np.testing.assert_array_equal(
        intrinsic.avoid_by_accelerating(north, previous=(0.7, 0.9)), [0.7, -1 / 3])


def test_eq9_keep_is_reset_by_the_agent_at_a_trial_end_and_ignored_by_eq8():
    west, quiet = np.eye(8)[4], np.full(8, 0.1)
    fb = intrinsic.fallback_for("eq9-10", "avoidance", 0.0, eq9_dead_zone="keep")
    ag = ebrl.Agent(ebrl.Config(memory_size=8, exploration_rate=1.0), 8, 2, fb, seed=0)
    for readings, last, want in ((west, False, [1 / 3, 0]), (quiet, True, [1 / 3, 0]),
                                 (quiet, False, [0, 0])):
        np.testing.assert_array_equal(ag.act(readings), want)
        ag.learn(0.0, last)
    assert intrinsic.fallback_for("eq8", "avoidance", eq9_dead_zone="keep").last is None


def test_random_in_avoidance_add_is_avoidance_plus_random_clipped():
    """The same draws in both: one uniform, then the Gaussian when it is below the rate.
    "replace" returns the random action, "add" eq 8's action plus it, clipped."""
    readings = np.array([0.0, 0, 0.4, 0, 0, 0, 0])  # eq 8: 3 * 0.4 / 6 = 0.2
    a_avoid = intrinsic.avoid_by_turning(readings)
    assert a_avoid == pytest.approx(0.2)
    replace = intrinsic.fallback_for("eq8", "avoidance", 0.2)
    add = intrinsic.fallback_for("eq8", "avoidance", 0.2, random_in_avoidance="add")
    r1, r2, r3 = (np.random.default_rng(5) for _ in range(3))
    kinds = set()
    for _ in range(400):
        u = r3.random()
        random = intrinsic.random_action(r3, 1)[0] if u < 0.2 else None
        a_rep, a_add = replace(readings, r1)[0], add(readings, r2)[0]
        if random is None:
            assert a_rep == a_add == a_avoid
            kinds.add("avoid")
        else:
            assert a_rep == random
            assert a_add == min(max(a_avoid + random, -1.0), 1.0)
            kinds.add("clipped" if abs(a_avoid + random) > 1 else "sum")
    assert kinds == {"avoid", "sum", "clipped"}
    assert r1.random() == r2.random() == r3.random()  # the same number of draws
    # eq 9-10, two axes: clipped per axis.
    add2 = intrinsic.fallback_for("eq9-10", "avoidance", 1.0, random_in_avoidance="add")
    west = np.eye(8)[4]
    rng, copy = np.random.default_rng(1), np.random.default_rng(1)
    copy.random()
    want = np.clip(intrinsic.avoid_by_accelerating(west) + intrinsic.random_action(copy, 2), -1, 1)
    np.testing.assert_array_equal(add2(west, rng), want)


@pytest.mark.parametrize("behaviour,dead_zone,mode", [
    ("eq8", "zero", "replace"), ("eq8", "zero", "add"),
    ("eq9-10", "zero", "replace"), ("eq9-10", "keep", "add"), ("eq9-10", "keep", "replace")])
def test_the_compiled_fallback_is_the_python_one(behaviour, dead_zone, mode):
    """The paper's avoidance runs as one compiled fallback_act; the same avoid function
    behind a wrapper (as an evolved genome's is) runs the Python steps: the same
    actions, choices, held accelerations and draws."""
    compiled = intrinsic.fallback_for(behaviour, "avoidance", 0.3, eq9_dead_zone=dead_zone,
                                      random_in_avoidance=mode)
    assert compiled.compiled
    avoid, dim = intrinsic.BEHAVIOURS[behaviour]
    python = intrinsic.Intrinsic(lambda s, **kw: avoid(s, **kw), dim, 0.3,
                                 random_in_avoidance=mode, hold=compiled.last is not None)
    assert not python.compiled
    r1, r2, readings = np.random.default_rng(4), np.random.default_rng(4), np.random.default_rng(9)
    n = 7 if behaviour == "eq8" else 8
    for step in range(2000):
        s = readings.integers(0, 256, n) / 255.0 * (step % 3 != 0)  # a third all quiet
        a, b = compiled(s, r1), python(s, r2)
        assert a.tobytes() == b.tobytes() and compiled.choice == python.choice, step
        if compiled.last is not None:
            assert compiled.last.tobytes() == python.last.tobytes()
        if step % 97 == 0:
            compiled.reset(), python.reset()
    assert r1.random() == r2.random()


def test_eq8_sums_with_fused_multiply_adds():
    """eq 8's sum: the first product, then each next one fused with the sum (one
    rounding each, computed here exactly with fractions), as numpy's dot sums on the
    machines the results come from; within a rounding of np.dot anywhere."""
    from fractions import Fraction

    def fma(a, b, c):
        return float(Fraction(a) * Fraction(b) + Fraction(c))

    rng = np.random.default_rng(0)
    for n in range(2, 17):
        half = n // 2
        for _ in range(500):
            s = rng.integers(0, 256, n) / 255.0
            d = s[:half] - s[: -half - 1: -1]
            total = 1.0 * d[0]
            for i in range(1, half):
                total = fma(float(i + 1), d[i], total)
            assert intrinsic.eq8(s) == total / (half * (half + 1) // 2), (n, s)
            assert intrinsic.eq8(s) == pytest.approx(
                np.dot(np.arange(1, half + 1), d) / (half * (half + 1) // 2), abs=1e-15)


def test_with_oldest_forgetting_reliability_changes_no_action():
    """Reliability is used only to choose what to forget: with "oldest", eq 7's scope and
    the initial reliability leave every action as it was."""
    base, _ = stream("groups_8_2", forgetting="oldest")
    for other in ({"initial_reliability": 0.0}, {"eq7_scope": "decided_only"}):
        actions, _ = stream("groups_8_2", forgetting="oldest", **other)
        assert np.array_equal(actions, base), other
