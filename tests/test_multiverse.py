"""`ebrl multiverse`: the design's resolution, the factors from the registry and the
protocols, the claims as `ebrl report` judges them, the effects, the refusals, and (slow)
the command on a tiny design and its resume."""
import dataclasses
import math
from types import MappingProxyType

import numpy as np
import pytest

from experiments.outputs import multiverse as mv
from experiments.running import execution
from experiments.studies import design, multiverse
from helpers import ebrl_here
from tasks import protocols
from tasks import readings as registry
from tasks.robots import PAPER_ROBOTS, ROBOTS

#: Montgomery's 2^(5-1)_V, I = ABCDE, in standard order (Design and Analysis of
#: Experiments, the principal fraction: E = ABCD), as printed.
TEXTBOOK_5_1 = """
- - - - +
+ - - - -
- + - - -
+ + - - +
- - + - -
+ - + - +
- + + - +
+ + + - -
- - - + -
+ - - + +
- + - + +
+ + - + -
- - + + +
+ - + + -
- + + + -
+ + + + +
"""


@pytest.mark.parametrize("k", range(1, design.MAX_FACTORS + 1))
def test_main_effects_and_two_factor_interactions_are_not_aliased(k):
    d = design.fractional_factorial(k)
    x, names = design.model_matrix(d.matrix)
    assert x.shape[1] == 1 + k + k * (k - 1) // 2
    # mutually orthogonal: each column's product with another sums to 0, with itself to N
    assert np.array_equal(x.T @ x, d.runs * np.eye(x.shape[1]))
    assert np.linalg.matrix_rank(x) == x.shape[1]
    assert d.resolution is None or d.resolution >= 5
    assert len({tuple(r) for r in d.matrix}) == d.runs       # no universe twice
    assert (d.matrix[0] == -1).all()                          # the first: every factor plain
    assert d.runs == {1: 2, 2: 4, 3: 8, 4: 16, 5: 16, 6: 32, 7: 64, 8: 64}.get(
        k, 128 if k <= 11 else 256)


def test_a_textbook_design():
    printed = np.array([[1 if c == "+" else -1 for c in line.split()]
                        for line in TEXTBOOK_5_1.strip().splitlines()])
    ours = design.fractional_factorial(5)
    assert ours.generators == ("E=ABCD",) and ours.resolution == 5
    # the same base in the same order; E's sign the other fraction's, so that it holds the
    # all-minus row (I = -ABCDE)
    assert np.array_equal(ours.matrix[:, :4], printed[:, :4])
    assert np.array_equal(ours.matrix[:, 4], -printed[:, 4])
    assert design.fractional_factorial(8).generators == ("G=ABCD", "H=ABEF")
    assert design.resolution(6, [design._mask("ABCD"), design._mask("ABEF")]) == 5
    assert design.resolution(6, [design._mask("ABC"), design._mask("DEF")]) == 4
    with pytest.raises(ValueError, match="1 to 17 factors"):
        design.fractional_factorial(18)


def _acting(spec):
    """A run's agent and task readings that act on its robot and condition, as run."""
    config = dataclasses.asdict(spec.agent_config()) | dataclasses.asdict(spec.task_config())
    return {n: multiverse.effective(spec.robot, n, config[n]) for n in config
            if n in registry.READING_BY_NAME
            and registry.applies(registry.READING_BY_NAME[n], ROBOTS[spec.robot], spec.condition)}


def _same_as_protocol(universe, protocol, overrides=True):
    for robot in PAPER_ROBOTS:
        for condition in ("random", "avoidance"):
            mine = execution.RunSpec(robot, condition, 0, 1, universe.overrides(robot, condition))
            theirs = execution.RunSpec(robot, condition, 0, 1, protocol=protocol)
            if _acting(mine) != _acting(theirs):
                return False
    return True


def test_no_factor_varies_a_stated_value_or_a_printed_equation():
    """The readings held plain (multiverse.HELD_PLAIN: a value the paper states, an
    equation it prints) are no factor's, and the protocols set none of them apart, so
    that none becomes a factor of its own; a factor read from a contradiction in the text
    quotes both sides."""
    named = {n for f in multiverse.factors() for names in f.readings.values() for n in names}
    assert not named & set(multiverse.HELD_PLAIN)
    assert {"blocked_move", "eq7_walk", "random_demand"} <= set(multiverse.HELD_PLAIN)
    assert all(name in registry.READING_BY_NAME for name in multiverse.HELD_PLAIN)
    assert [f.key for f in multiverse.factors()] == [f.key for f in multiverse.FACTORS]
    assert named | set(multiverse.HELD_PLAIN) == set(registry.READING_BY_NAME)  # each, one or other
    for key in ("eq7_signal", "thrust"):  # both sides of the contradiction quoted
        sentence = next(f for f in multiverse.FACTORS if f.key == key).sentence
        assert sentence.count('"') >= 4 and "against it" in sentence, key
    thrust = next(f for f in multiverse.FACTORS if f.key == "thrust")
    assert multiverse.levels(thrust, "floating") == multiverse.Levels(
        {"thrust": "scaled"}, {"thrust": "demand"}, "alternative")
    assert multiverse.levels(thrust, "two_wheel").source == "inert"


def test_the_factors_come_from_the_registry_and_the_protocols():
    factor_list = multiverse.factors()
    assert len(factor_list) >= 8
    for robot in PAPER_ROBOTS:
        drive = ROBOTS[robot].drive
        named = [n for f in factor_list for n in f.names(drive)]
        assert len(named) == len(set(named))  # a reading in one factor only
        for f in factor_list:
            for name, value in f.alternatives:
                registry.READING_BY_NAME[name].check(value)
            lv = multiverse.levels(f, robot)
            for name, value in lv.plain.items():
                assert value == dict(protocols.LITERAL.readings)[name]
                registry.READING_BY_NAME[name].check(lv.alternative[name])
            if lv.source == "adopted":
                assert all(multiverse.effective(robot, n, v) == multiverse.effective(
                    robot, n, multiverse.adopted_value(robot, n)) for n, v in lv.alternative.items())
    # every reading the adopted protocol sets apart from the literal one is some factor's
    d, universes = multiverse.universes(factor_list)
    assert universes[0].marks == ("literal",) and universes[0].row == 0
    current = next(u for u in universes if "current" in u.marks)
    assert _same_as_protocol(universes[0], "literal")
    assert _same_as_protocol(current, "adopted")
    assert not _same_as_protocol(universes[1], "literal")


def _protocol_8(two_wheel_body=(("radius", 1.5), ("leftover_turn", "commanded"))):
    """Protocol 8 (tasks.protocols.ADOPTED as it landed: the two-wheel move stopped at
    contact, stated), with the two-wheel body's open values (its radius and the leftover
    turn's way) as its fit may choose them."""
    return protocols.Protocol(
        "adopted", 8,
        readings=(("policy_threshold", 0.3), ("random_demand", "gaussian"),
                  ("random_in_avoidance", "replace")),
        drives=MappingProxyType({
            "two_wheel": (("leftover_turn", "away"),),
            "floating": (("eq9_dead_zone", "keep"), ("action_noise", 0.17273080599893353),
                         ("velocity_noise", 0.06931187891441754), ("velocity_code", "code"))}),
        robots=MappingProxyType({
            "two_wheel": (("blocked_move", "stop"),) + two_wheel_body,
            "floating": (("bump", "stop"), ("radius", 2.477124155927907))}))


def test_the_design_follows_the_adopted_protocol(monkeypatch):
    monkeypatch.setattr(protocols, "ADOPTED", _protocol_8())
    factor_list = multiverse.factors()
    assert [f.key for f in factor_list] == [f.key for f in multiverse.FACTORS]  # none extra
    d, universes = multiverse.universes(factor_list)
    assert d.runs == 128 and d.resolution == 5 and len(factor_list) == 11
    assert d.generators == ("H=ABCG", "J=BCDE", "K=ACDF", "L=ABCDEFG")
    body = next(f for f in factor_list if f.key == "body")
    # the literal two-wheel body (the file's radius, the commanded turn): its alternative
    # is the rest turned away; the floating body is the adopted (fitted) one
    assert multiverse.levels(body, "two_wheel") == multiverse.Levels(
        {"radius": None, "leftover_turn": "commanded"},
        {"radius": None, "leftover_turn": "away"}, "alternative")
    assert multiverse.levels(body, "floating").source == "adopted"
    keys = [f.key for f in factor_list]
    up = {r: [k for k, c in zip(keys, multiverse.current_codes(r)) if c > 0]
          for r in PAPER_ROBOTS}
    assert up == {"two_wheel": ["threshold"], "floating": ["threshold", "body"]}
    current = universes[-1]
    assert current.name == "current" and current.row is None and current.adopted
    # the current universe gives the adopted protocol's own values: the radius 1.5, not
    # the plain level's None (the file's), which runs other bits
    assert current.readings("two_wheel")["radius"] == 1.5
    # a fitted two-wheel body is the body's alternative, whole
    monkeypatch.setattr(protocols, "ADOPTED", _protocol_8(
        (("radius", 2.0), ("leftover_turn", "away"))))
    assert multiverse.levels(body, "two_wheel") == multiverse.Levels(
        {"radius": None, "leftover_turn": "commanded"},
        {"radius": 2.0, "leftover_turn": "away"}, "adopted")
    assert multiverse.current_codes("two_wheel") == multiverse.current_codes("floating")
    # a reading that no factor names, set apart by a protocol, becomes a factor
    monkeypatch.setattr(protocols, "ADOPTED", dataclasses.replace(
        _protocol_8(), readings=_protocol_8().readings + (("episode", "continuing"),)))
    assert multiverse.factors()[-1].key == "episode"
    assert multiverse.design_for(multiverse.factors()).runs == 256


def test_chosen_factors_and_the_first_universes():
    chosen = multiverse.select(["threshold", "body", "exploration"])
    d, universes = multiverse.universes(chosen, 3)
    assert d.runs == 8 and [u.name for u in universes] == ["u001", "u002", "u003", "current"]
    keys = [f.key for f in multiverse.factors()]
    for u in universes[:3]:  # a factor not chosen stays plain
        assert all(c < 0 for k, c in zip(keys, u.codes["two_wheel"])
                   if k not in ("threshold", "body", "exploration"))
    with pytest.raises(ValueError, match="unknown factor 'colour'"):
        multiverse.select(["colour"])


def _runs(per_seed, steps=None):
    """Synthetic complete runs: {(robot, condition): [(first, per_trial, goals) per seed]}."""
    runs = {}
    for (robot, condition), values in per_seed.items():
        budget = steps or ROBOTS[robot].budget
        for seed, (first, per, goals) in enumerate(values):
            runs[(robot, condition, seed)] = {
                "metrics": {"first_trial_steps": first, "steps_per_trial": per, "goals": goals},
                "parameters": {"steps": budget, "drive": ROBOTS[robot].drive, "learner": "ebrl"},
                "memory_decisions": 0, "seconds": 1.0}
    return runs


def _universe_runs(rng, scale=1.0, floating_slow=False):
    out = {}
    for robot, n in (("two_wheel", 30_000), ("floating", 100_000)):
        for condition, first in (("random", 6000), ("avoidance", 1000)):
            f = rng.gamma(2.0, first * scale / 2, 6)
            per = f * (0.6 if condition == "random" else 0.3) * (3 if floating_slow else 1)
            goals = np.maximum(1, (n / per).astype(int))
            out[(robot, condition)] = list(zip(f.tolist(), per.tolist(), goals.tolist()))
    return _runs(out)


def test_the_claims_are_judged_as_the_report_judges_them():
    rng = np.random.default_rng(1)
    for i in range(6):
        record = mv.universe_record(_universe_runs(rng, floating_slow=i % 2 == 1))
        assert mv.agrees_with_report(record)
        assert set(record["claims"]) == {f"C{n}" for n in range(1, 11)}
        assert len(record["figures"]) == 12
    c5 = record["claims"]["C5"]
    assert 0 <= c5["ci"][0] <= c5["value"] <= c5["ci"][1] <= 1
    assert mv.wilson(0, 10)[0] == 0 and math.isclose(mv.wilson(5, 10)[1], 0.7634, abs_tol=1e-4)
    # below the paper's budget C5 and C6 are not judged
    capped = mv.universe_record(_runs({k: [(100, 50, 3)] * 3 for k in
                                       [(r, c) for r in PAPER_ROBOTS for c in ("random", "avoidance")]},
                                      steps=500))
    assert capped["claims"]["C5"]["holds"] is None and capped["claims"]["C6"]["holds"] is None


def test_effects_are_recovered_from_the_design():
    d = design.fractional_factorial(8)
    x = d.matrix.astype(float)
    y = 0.4 * x[:, 0] - 0.2 * x[:, 3] + 0.3 * x[:, 1] * x[:, 5]
    fit = mv.fit_effects(d.matrix, y)
    assert np.allclose(fit["mains"], [0.8, 0, 0, -0.4, 0, 0, 0, 0], atol=1e-12)
    assert math.isclose(fit["pairs"][(1, 5)], 0.6) and \
        max(abs(v) for k, v in fit["pairs"].items() if k != (1, 5)) < 1e-12
    first = multiverse.run_order(d.runs)[:24]  # a partial run: too few for the interactions
    mains_only = mv.fit_effects(d.matrix[first], y[first])
    assert mains_only is not None and mains_only["pairs"] == {}
    assert mv.fit_effects(d.matrix[:4], y[:4]) is None
    assert mv.fit_effects(d.matrix[:32], y[:32]) is None  # the standard order's first half


def test_steps_per_trial_both_ways():
    """The analysis choice: a run's steps per trial as the mean of its completed trials,
    or its budget over its goals (the unfinished last trial counted), from one record."""
    record = {"robot": "two_wheel", "steps": 1000, "trials": [500, 100, 200],
              "memory_decisions": 7, "seconds": 1.0}
    mean, budget = (mv.run_of(record, d)["metrics"] for d in mv.DEFINITIONS)
    assert mean["steps_per_trial"] == 800 / 3 and budget["steps_per_trial"] == 1000 / 3
    assert mean["first_trial_steps"] == budget["first_trial_steps"] == 500
    assert mean["goals"] == 3
    none = mv.run_of(dict(record, trials=[]), "budget")["metrics"]
    assert none["steps_per_trial"] is None and none["goals"] == 0
    assert [c.key for c in mv.CLAIMS if mv.by_definition(c)] == ["C2", "C3", "C4", "C8",
                                                                  "C9", "C10"]


def test_the_analysis_and_the_curves(tmp_path):
    from experiments.outputs import multiverse_report as mr
    chosen = multiverse.select(["threshold", "body", "exploration", "eq7_scope", "thrust"])
    d, universes = multiverse.universes(chosen)
    rng = np.random.default_rng(2)
    body = [f.key for f in multiverse.factors()].index("body")
    records = {}
    for u in universes:
        record = mv.universe_record(_universe_runs(
            rng, scale=2.0 if u.codes["floating"][body] > 0 else 1.0,
            floating_slow=u.codes["floating"][body] > 0))
        records.update({(u.name, definition): record for definition in mv.DEFINITIONS})
    factor_list = multiverse.factors()
    analysis = mv.analyse(factor_list, chosen, universes, records)
    assert analysis["C1"]["judged"] == d.runs  # the definition does not act on C1
    assert analysis["C9"]["judged"] == 2 * d.runs  # both definitions of steps per trial
    assert mv.keys(factor_list, chosen)[-1] == mv.CHOICE
    # the body triples the floating robot's shrinks (log 3), and nothing else moves them:
    # nor the definition (the same records under both here)
    assert np.allclose(analysis["C9"]["effects"]["mains"], [0, 0, 0, math.log(3), 0, 0],
                       atol=1e-9)
    assert analysis["C1"]["effects"]["mains"][-1] is None
    text = mr.effects_tables(analysis, factor_list, chosen)
    assert "`body`" in text and f"`{mv.CHOICE}`" in text
    path = mr.spec_curve(mv.CLAIMS[8], factor_list, chosen, universes, records,
                         tmp_path / "spec_C9.png")
    assert path.read_bytes()[:4] == b"\x89PNG"
    csv_text = mv.table(factor_list, universes, records)
    assert len(csv_text.strip().splitlines()) == 2 * len(universes) + 1
    assert csv_text.splitlines()[1].startswith("u001,1,literal,mean,1,")
    assert csv_text.splitlines()[2].startswith("u001,1,literal,budget,1,")
    assert "is `current`, run beside the design" in mr.protocols_text(universes, factor_list)


BAD = [
    (["--universes", "0"], "positive"),
    (["--universes", "100000"], "--universes must be at most"),
    (["--factors", "colour"], "unknown factor 'colour'"),
    (["--factors", "threshold", "--universes", "3"], "at most 2"),
    (["--seeds", "9-3"], "reversed"),
    (["--steps", "0"], "positive"),
    (["--workers", "0"], "positive"),
    (["--backend", "mpi"], "mpi"),
    (["--out", "a_file/sub"], "--out"),
    (["--records", "a_file"], "--records"),
    (["--report-only"], "no records at"),
]


@pytest.mark.parametrize("args,message", BAD, ids=[" ".join(a) for a, _ in BAD])
def test_bad_options_are_refused_in_one_line(tmp_path, args, message):
    (tmp_path / "a_file").write_text("")
    proc = ebrl_here("multiverse", *args, cwd=tmp_path)
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1 and message in lines[0], proc.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a_file"]  # nothing written


def test_the_docs_list_every_factor_with_its_readings():
    from helpers import ROOT
    text = (ROOT / "docs" / "interpretation.md").read_text()
    section = text.split("## The multiverse (`ebrl multiverse`)")[1].split("\n## ")[0]
    rows = {line.split("|")[1].strip().strip("`"): line for line in section.splitlines()
            if line.startswith("| `")}
    assert list(rows) == [f.key for f in multiverse.FACTORS]
    for f in multiverse.FACTORS:
        readings_cell = rows[f.key].split("|")[2]
        for names in f.readings.values():
            assert all(f"`{n}`" in readings_cell for n in names), (f.key, readings_cell)
        quote = f.sentence.split('"')[1].split(" ...")[0]
        assert quote in rows[f.key], (f.key, quote)
    held = section.split("**Held plain, not factors**")[1].split("\n\n")[0]
    assert all(f"`{name}`" in held for name in multiverse.HELD_PLAIN)
    assert f"`{mv.CHOICE}`" not in rows and "`DEFINITIONS`" in section


def test_the_analysis_with_two_factor_effects_is_written_as_json():
    """A full design identifies the two-factor effects, keyed (i, j) by analyse; the
    multiverse's JSON names them by the keys (the first finished 10-seed run of the
    design raised TypeError at its last write)."""
    import itertools
    import json

    from experiments.outputs import multiverse as mv
    codes = [list(c) for c in itertools.product((-1, 1), repeat=3)]
    y = [1.0 + 2 * a + 0.5 * a * b for a, b, _ in codes]
    effects = mv.fit_effects(codes, y)
    assert effects["pairs"][(0, 1)] == pytest.approx(1.0)
    analysis = {"c1": {"judged": 8, "effects": effects}, "c2": {"judged": 0, "effects": None}}
    text = json.dumps(mv.analysis_json(analysis, ["a", "b", "c"]), sort_keys=True)
    back = json.loads(text)
    assert back["c1"]["effects"]["pairs"]["a x b"] == pytest.approx(1.0)
    assert back["c1"]["effects"]["mains"][0] == pytest.approx(4.0)
    assert back["c2"]["effects"] is None


def test_the_cost_section_by_hand():
    """Two calls of two workers (one stopped), two runs of 10 and 30 s; bench at 50 and 100
    us a step over 1e6 and 2e6 steps: 250 s of one core, 125 s on two; raw physics and the
    reference pass, 20 + 10 and 40 + 20 us: 150 s, 75 s on two."""
    from experiments.outputs import multiverse_report as mr
    timing = [{"runs_made": 1, "seconds": 100.0, "workers": 2, "interrupted": True},
              {"runs_made": 1, "seconds": 50.0, "workers": 2}]
    bench = {"two_wheel": {"fused_loop": 50.0, "raw_physics": 20.0, "reference_pass": 10.0},
             "floating": {"fused_loop": 100.0, "raw_physics": 40.0, "reference_pass": 20.0}}
    lines = mr.cost_text(2, [10.0, 30.0], timing, bench, {"two_wheel": 1e6, "floating": 2e6})
    assert "made by 2 call(s) of `ebrl multiverse` (1 stopped and resumed) in **2.5 min**" \
        in lines[0]
    assert "the longest 30 s); the floor on 2 worker(s): 20 s." in lines[1]
    assert "times the 2 runs' steps: 4.2 min of one core; the floor on 2 worker(s): 2.1 min." \
        in lines[2]
    assert "a step: 2.5 min of one core, 1.2 min on 2 worker(s)." in lines[2]
    # an older bench.json without the parts: the fused loop's line alone
    old = {r: {"fused_loop": b["fused_loop"]} for r, b in bench.items()}
    line = mr.cost_text(2, [10.0, 30.0], timing, old, {"two_wheel": 1e6, "floating": 2e6})[2]
    assert line.endswith("2.1 min.") and "reference pass" not in line
