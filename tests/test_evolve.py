"""Evolved intrinsic behaviours (issue 18): the genome family (ebrl.behaviour) on hand-made
readings, the paper's rules as files that reproduce the default runs bit for bit,
`ebrl run --behaviour`, bad genomes, and a tiny `ebrl evolve` that runs, resumes and is
deterministic for a seed."""
import dataclasses
import json
import math
import pathlib
import shutil

import numpy as np
import pytest

from ebrl import behaviour as genomes
from ebrl import intrinsic
from experiments.studies import evolve, study
from experiments.running import execution
from helpers import ROOT, ebrl, ebrl_here

PAPER_FILES = {"eq8": ROOT / "behaviours" / "paper_eq8.json",
               "eq9-10": ROOT / "behaviours" / "paper_eq9-10.json"}


# -- the family on hand-made readings ---------------------------------------------------
def test_paper_files_are_the_papers_rules_and_current():
    from tasks.robots import ROBOTS
    for robot in evolve.PAPER_FILE_ROBOTS:
        entry = ROBOTS[robot]
        path = PAPER_FILES[entry.avoidance]
        # Made by evolve.write_paper("behaviours"); rerun it if a robot's readings change.
        expected = evolve.paper_genome(entry)
        assert path.read_text() == genomes.dumps(expected), (
            f"{path} is stale: python -c 'from experiments.studies import evolve; "
            "evolve.write_paper(\"behaviours\")'")
        g = genomes.load(path)
        assert g == expected and genomes.is_paper_rule(g)
        config = execution.RunSpec(robot, "avoidance", 0, 1).agent_config()
        assert g.initial_reliability == config.initial_reliability
    t = genomes.load(PAPER_FILES["eq8"])
    assert t.weights == (1 / 6, 2 / 6, 3 / 6, 0.0, -3 / 6, -2 / 6, -1 / 6)  # i / sum(i), mirrored
    a = genomes.load(PAPER_FILES["eq9-10"])
    # eq 9's dead zone keeps the previous acceleration: the floating drive's reading.
    assert (a.threshold, a.gain, a.hold, a.bias) == (0.25, 1.0, 1.0, (0.0, 0.0))
    assert (t.random_rate, t.random_sd) == (a.random_rate, a.random_sd) == (0.2, 0.5)


def test_the_formulas_at_the_papers_point_are_eq8_and_eq9_10():
    rng = np.random.default_rng(3)
    t, a = genomes.paper("eq8"), genomes.paper("eq9-10")
    keep = dataclasses.replace(a, hold=1.0)
    for _ in range(2000):
        s7, s8, prev = rng.random(7), rng.random(8), rng.uniform(-1, 1, 2)
        assert t.avoid(s7) == pytest.approx(intrinsic.avoid_by_turning(s7), abs=1e-15)
        assert a.avoid(s8) == pytest.approx(intrinsic.avoid_by_accelerating(s8), abs=1e-15)
        assert keep.avoid(s8, prev) == pytest.approx(
            intrinsic.avoid_by_accelerating(s8, previous=prev), abs=1e-15)
    # eq 8 on 5 beams: weights 1/3, 2/3 and their mirror.
    assert genomes.paper("eq8", 5).weights == (1 / 3, 2 / 3, 0.0, -2 / 3, -1 / 3)


def test_each_turning_parameter_moves_the_turn_as_documented():
    paper = genomes.paper("eq8")
    left = [0.6, 0, 0, 0, 0, 0, 0]            # something at the leftmost beam only
    assert paper.avoid(left) == pytest.approx(0.6 / 6)   # eq 8: turn right, 1/6 of 0.6
    w = list(paper.weights)
    w[0] = 0.5
    assert dataclasses.replace(paper, weights=tuple(w)).avoid(left) == pytest.approx(0.3)
    w[0] = 0.0                                  # a zero weight ignores its beam
    assert dataclasses.replace(paper, weights=tuple(w)).avoid(left) == 0.0
    w[0] = -0.5                                 # a negative weight turns towards it
    assert dataclasses.replace(paper, weights=tuple(w)).avoid(left) == pytest.approx(-0.3)
    assert dataclasses.replace(paper, bias=0.2).avoid([0] * 7) == pytest.approx(0.2)
    assert dataclasses.replace(paper, bias=-0.2).avoid(left) == pytest.approx(0.1 - 0.2)
    assert dataclasses.replace(paper, gain=2.0).avoid(left) == pytest.approx(0.2)
    assert dataclasses.replace(paper, gain=20.0).avoid(left) == 1.0      # saturates
    assert dataclasses.replace(paper, gain=20.0, bias=-1).avoid(left) == -1.0


def test_each_accelerating_parameter_moves_the_acceleration_as_documented():
    paper = genomes.paper("eq9-10")
    east = [1.0, 0, 0, 0, 0, 0, 0, 0]           # a wall at the East beam only
    north = [0, 0, 1.0, 0, 0, 0, 0, 0]
    # eq 10: b_h = -0.5, eq 9: (-0.5 + 0.25) / 0.75 = -1/3 (away, West); b_v = 0.
    assert paper.avoid(east) == pytest.approx([-1 / 3, 0.0])
    # weights_v None: b_h's weights turned by 90 degrees, so North pushes South.
    assert paper.avoid(north) == pytest.approx([0.0, -1 / 3])
    wh = list(paper.weights_h)
    wh[0] = -1.0
    assert dataclasses.replace(paper, weights_h=tuple(wh)).avoid(east) == pytest.approx([-1.0, 0.0])
    # weights_v given: b_v's own weights (here none on North: no vertical response).
    assert dataclasses.replace(paper, weights_v=(0.0,) * 8).avoid(north) == pytest.approx([0, 0])
    # b_v = 1 (towards the wall): (1 - 0.25) / 0.75 = 1.
    assert dataclasses.replace(paper, weights_v=(0, 0, 1.0, 0, 0, 0, 0, 0)).avoid(north) == \
        pytest.approx([0.0, 1.0])
    # bias: a drift with nothing in view, past the threshold: (0.5 - 0.25) / 0.75.
    assert dataclasses.replace(paper, bias=(0.5, 0.0)).avoid([0] * 8) == pytest.approx([1 / 3, 0])
    assert dataclasses.replace(paper, bias=(0.0, -0.4)).avoid([0] * 8) == pytest.approx([0, -0.2])
    # threshold: 0.6 puts b_h = -0.5 in the dead zone; 0 makes a = b.
    assert dataclasses.replace(paper, threshold=0.6).avoid(east) == pytest.approx([0, 0])
    assert dataclasses.replace(paper, threshold=0.0).avoid(east) == pytest.approx([-0.5, 0])
    assert dataclasses.replace(paper, gain=2.0).avoid(east) == pytest.approx([-2 / 3, 0])
    assert dataclasses.replace(paper, gain=9.0).avoid(east) == pytest.approx([-1.0, 0])
    # hold: the share of the previous acceleration kept in the dead zone.
    prev = np.array([0.6, -0.4])
    assert dataclasses.replace(paper, hold=0.5).avoid([0] * 8, prev) == pytest.approx([0.3, -0.2])
    assert dataclasses.replace(paper, hold=1.0).avoid([0] * 8, prev) == pytest.approx([0.6, -0.4])
    assert dataclasses.replace(paper, hold=0.0).avoid([0] * 8, prev) == pytest.approx([0, 0])
    # Through the fallback (no random action): it holds its own last output.
    fb = genomes.fallback(dataclasses.replace(paper, hold=0.5, random_rate=0.0), "avoidance")
    rng = np.random.default_rng(0)
    assert fb(east, rng) == pytest.approx([-1 / 3, 0])
    assert fb([0] * 8, rng) == pytest.approx([-1 / 6, 0])
    fb.reset()                                   # a trial's end: nothing held
    assert fb([0] * 8, rng) == pytest.approx([0, 0])


def test_random_share_and_spread_and_learning_variables():
    left = [0.6, 0, 0, 0, 0, 0, 0]
    g = dataclasses.replace(genomes.paper("eq8"), bias=0.05)     # off the paper's rule
    rng = np.random.default_rng(1)
    never = genomes.fallback(dataclasses.replace(g, random_rate=0.0), "avoidance")
    assert {round(float(never(left, rng)[0]), 12) for _ in range(200)} == {0.15}
    always = genomes.fallback(dataclasses.replace(g, random_rate=1.0, random_sd=0.3), "avoidance")
    draws = np.array([always(left, rng)[0] for _ in range(4000)])
    assert abs(draws.mean()) < 0.02 and draws.std() == pytest.approx(0.3, rel=0.05)
    half = genomes.fallback(dataclasses.replace(g, random_rate=0.5), "avoidance")
    share = np.mean([half(left, rng)[0] != 0.15 for _ in range(4000)])
    assert share == pytest.approx(0.5, abs=0.03)
    walk = genomes.fallback(dataclasses.replace(g, random_sd=0.1), "random")
    assert np.std([walk(left, rng)[0] for _ in range(4000)]) == pytest.approx(0.1, rel=0.05)
    # The learning variables' initial values and the random action reach the agent's config.
    g = dataclasses.replace(g, initial_reliability=0.3, initial_utility=0.25, random_rate=0.1,
                            random_sd=0.7)
    config = execution.RunSpec("two_wheel", "avoidance", 0, 10, behaviour=g).agent_config()
    assert (config.initial_reliability, config.initial_utility) == (0.3, 0.25)
    assert (config.intrinsic_random_rate, config.random_sd) == (0.1, 0.7)


# -- bit for bit --------------------------------------------------------------------------
STEPS = 2500


@pytest.mark.parametrize("robot", ["two_wheel", "floating"])
def test_the_paper_files_reproduce_the_default_runs_bit_for_bit(robot):
    from tasks.robots import ROBOTS
    genome = genomes.load(PAPER_FILES[ROBOTS[robot].avoidance])
    for condition in ("random", "avoidance"):
        default = execution.execute(execution.RunSpec(robot, condition, 3, STEPS))
        mine = execution.execute(execution.RunSpec(robot, condition, 3, STEPS, behaviour=genome))
        assert mine["trace"].tobytes() == default["trace"].tobytes(), condition
        assert mine["trial_ends"].tolist() == default["trial_ends"].tolist()
        assert mine["memory_decisions"] == default["memory_decisions"]
    if robot == "floating":  # the floating robot's reading "keep" is hold 1 (its file's);
        # hold 0 is the reading "zero", bit for bit
        assert genome.hold == 1.0
        zero = execution.execute(execution.RunSpec(robot, "avoidance", 3, STEPS,
                                                 (("eq9_dead_zone", "zero"),)))
        dropped = execution.execute(execution.RunSpec(robot, "avoidance", 3, STEPS,
                                                    behaviour=dataclasses.replace(genome, hold=0.0)))
        assert dropped["trace"].tobytes() == zero["trace"].tobytes()
        assert dropped["trace"].tobytes() != default["trace"].tobytes()


@pytest.mark.slow
def test_run_with_a_behaviour_file_records_it_and_matches_the_default(tmp_path):
    common = ["run", "--robot", "two_wheel", "--condition", "avoidance", "--seeds", "0",
              "--steps", 600, "--workers", 1, "--no-progress"]
    assert ebrl_here(*common, "--out", tmp_path / "default").returncode == 0
    proc = ebrl_here(*common, "--out", tmp_path / "paper", "--behaviour", PAPER_FILES["eq8"])
    assert proc.returncode == 0, proc.stderr
    run = pathlib.Path("two_wheel/avoidance/seed_000")
    config = json.loads((tmp_path / "paper" / run / "config.json").read_text())
    assert config["behaviour"] == json.loads(PAPER_FILES["eq8"].read_text())
    assert "behaviour" not in json.loads((tmp_path / "default" / run / "config.json").read_text())
    with np.load(tmp_path / "paper" / run / "trace.npz") as a, \
            np.load(tmp_path / "default" / run / "trace.npz") as b:
        assert a["trace"].tobytes() == b["trace"].tobytes()
    # Another genome never matches those runs: same folder, other parameters.
    other = tmp_path / "other.json"
    genomes.save(dataclasses.replace(genomes.paper("eq8"), bias=0.1), other)
    proc = ebrl_here(*common, "--out", tmp_path / "paper", "--behaviour", other)
    assert proc.returncode == 2 and "made with other parameters" in proc.stderr


def _bad(tmp_path, change=None, drop=None, text=None, behaviour="eq8"):
    data = genomes.to_dict(genomes.paper(behaviour))
    data.update(change or {})
    if drop:
        del data[drop]
    path = tmp_path / "bad.json"
    path.write_text(text if text is not None else json.dumps(data))
    return path


@pytest.mark.parametrize("kind,message", [
    ("missing", "missing field 'gain'"),
    ("unknown", "unknown field 'colour'"),
    ("length", "6 weights, but two_wheel has 7 beams"),
    ("length_h", "field weights_h: 7 values, need 8"),
    ("nan", "field bias: not a finite number"),
    ("range", "field random_rate: 1.5 is outside [0, 1]"),
    ("family", "a eq9-10 genome, but two_wheel uses eq8"),
    ("json", "not JSON"),
    ("set", "--set random_sd conflicts with --behaviour"),
    ("nofile", "No such file"),
])
@pytest.mark.slow
def test_bad_genomes_are_one_line_and_write_nothing(tmp_path, capsys, kind, message):
    extra = []
    path = {
        "missing": lambda: _bad(tmp_path, drop="gain"),
        "unknown": lambda: _bad(tmp_path, {"colour": 1}),
        "length": lambda: _bad(tmp_path, {"weights": [0.1] * 6}),
        "length_h": lambda: _bad(tmp_path, {"weights_h": [0.1] * 7}, behaviour="eq9-10"),
        "nan": lambda: _bad(tmp_path, text=json.dumps(genomes.to_dict(genomes.paper("eq8")))
                            .replace('"bias": 0.0', '"bias": NaN')),
        "range": lambda: _bad(tmp_path, {"random_rate": 1.5}),
        "family": lambda: _bad(tmp_path, behaviour="eq9-10"),
        "json": lambda: _bad(tmp_path, text="{not json"),
        "set": lambda: _bad(tmp_path),
        "nofile": lambda: tmp_path / "missing.json",
    }[kind]()
    if kind == "set":
        extra = ["--set", "random_sd=0.3"]
    out = tmp_path / "out"
    args = ["run", "--robot", "two_wheel", "--seeds", "0", "--steps", "10", "--out", str(out),
            "--behaviour", str(path), *extra]
    if kind == "missing":  # through a real process once
        proc = ebrl(*args)
        status, err = proc.returncode, proc.stderr
    else:                  # the same command line in this process (faster)
        status, err = _main(capsys, args)
    assert status == 2, err
    assert message in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def _main(capsys, args):
    """`ebrl ARGS` in this process: (exit status, stderr)."""
    from experiments import cli
    capsys.readouterr()
    try:
        status = cli.main(args)
    except SystemExit as e:  # argparse's own errors
        status = e.code
    return status, capsys.readouterr().err


# -- ebrl evolve --------------------------------------------------------------------------
EVOLVE = ["evolve", "--robot", "two_wheel", "--population", 4, "--seeds", 1000,
          "--steps", 1500, "--workers", 1, "--no-progress"]


def _study(out, name="evolve-two_wheel"):
    import optuna
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    return optuna.load_study(study_name=name, storage=study.storage_url(None, out))


def _record(out):
    return [(t.number, t.state.name, t.params, t.value) for t in _study(out).trials]


@pytest.mark.slow
def test_a_tiny_evolution_runs_resumes_and_is_deterministic(tmp_path, capsys):
    a, b, c = tmp_path / "a", tmp_path / "b", tmp_path / "c"
    proc = ebrl_here(*EVOLVE, "--generations", 1, "--out", a)
    assert proc.returncode == 0, proc.stderr
    trials = _study(a).trials
    assert len(trials) == 5 and all(t.state.name == "COMPLETE" for t in trials)
    # Trial 0: the paper's rule, whose runs are the default's (folder key with the genome).
    from tasks.robots import ROBOTS
    start = evolve.paper_genome(ROBOTS["two_wheel"])   # with the two-wheel robot's readings
    problem = evolve.Problem("two_wheel", start, evolve.fields(start), (1000,), 1500)
    assert trials[0].params == problem.x0()
    assert trials[0].user_attrs["rungs"][0]["goals"] == -trials[0].value
    spec = problem.specs(trials[0].params, (1000,))[0]
    config = json.loads((study.run_folder(a, spec) / spec.name / "config.json").read_text())
    assert config["behaviour"] == genomes.to_dict(start)
    assert len({t.params["gain"] for t in trials}) == 5          # generation 1 sampled apart
    best = genomes.load(a / "evolve-two_wheel_best.json")
    assert best.behaviour == "eq8" and (a / "evolve-two_wheel.md").exists()
    shutil.copytree(a, c)

    # The same command with one more generation resumes: 4 more trials, the first 5 kept.
    proc = ebrl_here(*EVOLVE, "--generations", 2, "--out", a)
    assert proc.returncode == 0 and "4 trials made now, 9 in the study" in proc.stdout
    # One study of two generations from scratch: the same trials, bit for bit.
    assert ebrl_here(*EVOLVE, "--generations", 2, "--out", b).returncode == 0
    assert _record(a) == _record(b)
    # Again: nothing to do (in this process: no run starts).
    proc = ebrl_here(*EVOLVE, "--generations", 2, "--out", a)
    assert proc.returncode == 0 and "0 trials made now, 9 in the study" in proc.stdout
    # The same study with other seeds (or steps, population, start, space): refused.
    before = (a / "study.db").read_bytes()
    status, err = _main(capsys, [str(x) for x in EVOLVE[:5]] + ["--seeds", "1001", "--out", str(a)])
    assert status == 2 and "made with other settings (seeds: [1000], now [1001])" in err
    assert (a / "study.db").read_bytes() == before

    # A kill mid-generation leaves a trial running: the next call fails it and asks its
    # genome again first.
    s = _study(c)
    s.sampler = problem.sampler(len(s.trials))
    left = s.ask(problem.distributions())
    proc = ebrl_here(*EVOLVE, "--generations", 2, "--out", c)
    assert proc.returncode == 0, proc.stderr
    trials = _study(c).trials
    assert trials[5].state.name == "FAIL" and trials[5].user_attrs["error"].startswith("interrupted")
    assert trials[6].params == left.params and trials[6].state.name == "COMPLETE"
    assert sum(t.state.name == "COMPLETE" for t in trials) == 9


@pytest.mark.slow
@pytest.mark.filterwarnings("error::RuntimeWarning")  # cmaes's at population 2: not the user's
def test_evolution_without_learning_never_lets_the_memory_act(tmp_path):
    out = tmp_path / "c"
    proc = ebrl_here("evolve", "--robot", "two_wheel", "--population", 2, "--generations", 1,
                     "--seeds", 1000, "--steps", 600, "--workers", 1, "--no-progress",
                     "--no-learning", "--out", out)
    assert proc.returncode == 0, proc.stderr
    trials = _study(out, "evolve-two_wheel-controller").trials
    assert len(trials) == 3 and not any(k.startswith("initial_") for k in trials[0].params)
    runs = list((out / "runs").glob("*/two_wheel/avoidance/seed_1000/run.json"))
    assert len(runs) == 3
    for path in runs:
        run = json.loads(path.read_text())
        assert run["memory_decisions"] == 0 and run["parameters"]["agent"]["exploration_rate"] == 1.0


@pytest.mark.parametrize("args,message", [
    (["--population", "1"], "--population must be at least 2"),
    (["--space", "colour"], "unknown field 'colour' in --space"),
    (["--no-learning", "--space", "initial_utility"], "learning variable"),
    (["--space", "weights_v", "--robot", "floating"], "--space weights_v needs"),
    (["--robot", "floating", "--start", "behaviours/paper_eq8.json"], "a eq8 genome, but floating"),
    (["--storage", "not a url://"], "bad --storage"),
    (["--seeds", "5-3"], "reversed seed range"),
])
@pytest.mark.slow
def test_bad_evolve_arguments_are_one_line_and_write_nothing(tmp_path, capsys, args, message):
    out = tmp_path / "ev"
    base = ["evolve", "--robot", "two_wheel"] if "--robot" not in args else ["evolve"]
    if args[0] == "--population":  # through a real process once
        proc = ebrl(*base, *args, "--out", out)
        status, err = proc.returncode, proc.stderr
    else:
        status, err = _main(capsys, [*base, *args, "--out", str(out)])
    assert status == 2, err
    assert message in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_study_keys_runs_by_genome_and_keeps_fits_keys():
    assert study.folder_key((("bump", "stop"),)) == study.folder_key((("bump", "stop"),), None)
    paper = genomes.paper("eq8")
    assert study.folder_key((), paper) != study.folder_key(())
    assert study.folder_key((), paper) != study.folder_key((), dataclasses.replace(paper, bias=0.1))
    assert math.isfinite(evolve.Problem("two_wheel", paper, ("gain",), (0,)).score(
        {}, {("two_wheel", "avoidance", 0): {"metrics": {"goals": 3, "steps_per_trial": 10.0,
                                                         "first_trial_steps": 12}}})[0])


@pytest.mark.slow
def test_evolve_report_sets_the_evolved_learner_beside_the_papers_rule(tmp_path):
    """A tiny evolution, the paper's rule and the evolved genome on three held-out seeds:
    EVOLVE.md's ratio is the hand-coded mean steps per trial over the evolved one, computed
    here from the runs' own run.json; folders not run are named; the RESULTS.md block."""
    evo, hand, evolved = tmp_path / "evolve", tmp_path / "results", tmp_path / "evolved"
    assert ebrl_here(*EVOLVE, "--generations", 1, "--out", evo).returncode == 0
    best = evo / "evolve-two_wheel_best.json"
    common = ["run", "--robot", "two_wheel", "--condition", "avoidance", "--seeds", "0-2",
              "--steps", 4000, "--workers", 1, "--no-progress"]
    assert ebrl_here(*common, "--out", hand).returncode == 0
    evolved.mkdir()
    assert ebrl_here(*common, "--behaviour", best, "--out", evolved / "learner").returncode == 0
    results_md = tmp_path / "RESULTS.md"
    results_md.write_text("# R\n\nkept above\n")
    out, figures = tmp_path / "EVOLVE.md", tmp_path / "figures"
    proc = ebrl_here("evolve-report", "--evolve", evo, "--hand", hand, "--evolved", evolved,
                     "--out", out, "--figures", figures, "--results", results_md)
    assert proc.returncode == 0, proc.stderr
    text = out.read_text()

    def mean_steps(folder):
        runs = [json.loads((folder / "two_wheel" / "avoidance" / f"seed_{s:03d}" / "run.json")
                           .read_text())["metrics"]["steps_per_trial"] for s in range(3)]
        runs = [v for v in runs if v is not None]    # a seed without a goal has none
        assert runs
        return sum(runs) / len(runs)

    row = next(line for line in text.splitlines()
               if line.startswith("| two_wheel | evolved for the learner |"))
    assert f"{mean_steps(hand) / mean_steps(evolved / 'learner'):.2f}x" in row
    assert "two_wheel, evolved as a controller" in text        # not run: named
    assert "`evolve-two_wheel-controller`: not run." in text
    assert (figures / "evolve-two_wheel_fitness.png").is_file()
    assert (figures / "evolved_traces_two_wheel.png").is_file()
    page = results_md.read_text()
    assert page.startswith("# R\n\nkept above") and row in page
    bad = ebrl_here("evolve-report", "--evolve", evo, "--hand", tmp_path / "nowhere", "--evolved",
                    evolved, "--out", tmp_path / "E2.md")
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1
    assert "nowhere" in bad.stderr and not (tmp_path / "E2.md").exists()
