"""Bad command lines, as a new user would type them, through the real command: each one
fails fast, in one line, without a traceback and writing nothing.

Every case runs in its own sandbox folder (the command's cwd), holding a regular file,
an empty folder and a folder named like a video; the sandbox must be unchanged after.
Each case runs the command's main() in this process (tests/helpers.py's ebrl_here: the
same parser, checks, line and exit status, without a fresh interpreter's second of
imports per case: the unit tier); a few cases also run as a fresh `python -m
experiments`, the whole way a user starts it (the slow tier).
"""
import os
import pathlib
import subprocess
import sys
import time

import pytest

from helpers import ebrl_here

ROOT = pathlib.Path(__file__).resolve().parents[1]
LIMIT_S = 10.0
BIG = "99999999999"
HUGE = "9" * 40
ROBOT_FILE = str(pathlib.Path(__file__).resolve().parents[1] / "models" / "two_wheel.xml")
RENDER = ["render", "--robot", "two_wheel", "--condition", "avoidance"]
REPORT_OK = ["report", "empty_dir"]  # a folder that passes the folder checks

#: (command line, a piece of the one-line message). Paths are relative to the sandbox.
CASES = [
    # run: unknown names
    (["run", "--robot", "tricycle"], "tricycle"),
    (["run", "--condition", "lazy"], "lazy"),
    (["run", "--backend", "mpi"], "mpi"),
    (["run", "--set", "colour=3"], "colour"),
    (["run", "--robot", "ant", "--set", "blocked_move=refuse"], "blocked_move=stop only"),
    (["run", "--set", "alpha"], "NAME=VALUE"),
    (["run", "--frobnicate"], "unrecognized arguments"),
    (["run", "extra"], "unrecognized arguments"),
    # run: seeds
    (["run", "--seeds", "9-3"], "reversed"),
    (["run", "--seeds", ""], "seed"),
    (["run", "--seeds", "abc"], "bad seed range"),
    (["run", "--seeds", "1.5"], "bad seed range"),
    (["run", "--seeds", "nan"], "bad seed range"),
    (["run", "--seeds", "0-" + BIG, "--steps", "1"], "seeds go up to 999,999"),
    (["run", "--seeds", HUGE], "seeds go up to"),
    (["run", "--seeds", "0-50000"], "at most 10,000 seeds"),
    (["run", "--seeds", "0-9000,20000-29000"], "at most 10,000 seeds"),
    # run: steps and workers
    (["run", "--steps", "0"], "positive"),
    (["run", "--steps", "-5"], "positive"),
    (["run", "--steps", "abc"], "not an integer"),
    (["run", "--steps", "1.5"], "not an integer"),
    (["run", "--steps", "nan"], "not an integer"),
    (["run", "--steps", BIG], "at most 10,000,000"),
    (["run", "--workers", "0"], "positive"),
    (["run", "--workers", "two"], "not an integer"),
    (["run", "--workers", "100000"], "at most 1,024"),
    # run: agent parameters, against ebrl.Config's own checks
    (["run", "--set", "alpha=2"], "alpha must be in (0, 1)"),
    (["run", "--set", "alpha=nan"], "not a finite number"),
    (["run", "--set", "alpha=abc"], "bad value for alpha"),
    (["run", "--set", "discount=1"], "discount must be in (0, 1)"),
    (["run", "--set", "exploration_rate=1.5"], "exploration_rate must be in [0, 1]"),
    (["run", "--set", "random_sd=-1"], "random_sd must be positive"),
    (["run", "--set", "variance_floor=inf"], "not a finite number"),
    (["run", "--set", "policy_threshold=-inf"], "not a finite number"),
    (["run", "--set", "memory_size=0"], "memory_size must be a positive integer"),
    (["run", "--set", "memory_size=2.5"], "not an integer"),
    (["run", "--set", "memory_size=" + BIG], "memory_size must be at most"),
    (["run", "--set", "recall_size=2000"], "must be at least recall_size"),
    (["run", "--set", "alpha=0.3", "--set", "alpha=0.4"], "more than once"),
    # run: readings, against their registry entries (tasks.readings)
    (["run", "--set", "bump=wobble"], "bump must be one of stop, grip, slide, bounce, got 'wobble'"),
    (["run", "--set", "eq9_dead_zone=sideways"], "eq9_dead_zone must be one of keep, zero"),
    (["run", "--set", "radius=0"], "radius must be positive"),
    (["run", "--set", "radius=9"], "radius must be at most 5 units"),
    (["run", "--set", "restitution=2"], "restitution must be at most 1"),
    (["run", "--set", "initial_reliability=1.5"], "initial_reliability must be at most 1"),
    (["sweep", "--param", "thrust", "--values", "scaled,rocket"], "thrust must be one of"),
    # run: output folders
    (["run", "--out", "a_file"], "not a folder"),
    (["run", "--out", "a_file/results"], "a_file is not a folder"),
    (["run", "--out", "missing/results"], "does not exist"),
    (["run", "--out", "/proc/ebrl_results"], "cannot write"),
    # sweep
    (["sweep", "--param", "colour"], "unknown --param"),
    (["sweep", "--values", ""], "--values is empty"),
    (["sweep", "--values", ",,"], "--values is empty"),
    (["sweep", "--values", "0.1,abc"], "bad value for policy_threshold"),
    (["sweep", "--values", "nan"], "not a finite number"),
    (["sweep", "--values", "0.1,0.10"], "more than once"),
    (["sweep", "--param", "alpha", "--values", "0.5,2"], "alpha must be in (0, 1)"),
    (["sweep", "--param", "memory_size", "--values", "4"], "must be at least recall_size"),
    (["sweep", "--seeds", "0-" + BIG], "seeds go up to"),
    (["sweep", "--steps", "0"], "positive"),
    (["sweep", "--robot", "tricycle"], "tricycle"),
    (["sweep", "--baseline", "missing"], "no results folder"),
    (["sweep", "--baseline", "a_file"], "no results folder"),
    (["sweep", "--out", "a_file/sweeps"], "a_file is not a folder"),
    (["sweep", "--out", "/proc/ebrl_sweeps"], "cannot write"),
    # report
    (["report"], "required"),
    (["report", "missing"], "no results folder"),
    (["report", "a_file"], "no results folder"),
    (["report", "/proc"], "cannot write"),
    (["report", "empty_dir"], "no complete runs"),
    (REPORT_OK + ["--results", "missing/RESULTS.md"], "does not exist"),
    (REPORT_OK + ["--results", "a_file/RESULTS.md"], "a_file is not a folder"),
    (REPORT_OK + ["--results", "empty_dir"], "is a folder"),
    (REPORT_OK + ["--results", "/proc/RESULTS.md"], "cannot write"),
    (REPORT_OK + ["--results", "RESULTS.md", "--figures", "a_file"], "not a folder"),
    (REPORT_OK + ["--results", "RESULTS.md", "--figures", "missing/figures"], "does not exist"),
    # render
    (["render", "--robot", "tricycle", "--condition", "avoidance", "--seed", "0",
      "--out", "v.mp4"], "tricycle"),
    (RENDER + ["--seed", "0"], "required: --out"),
    (RENDER + ["--seed", "-1", "--out", "v.mp4"], "must be at least 0"),
    (RENDER + ["--seed", "abc", "--out", "v.mp4"], "not an integer"),
    (RENDER + ["--seed", BIG, "--out", "v.mp4"], "at most 999,999"),
    (RENDER + ["--seed", "0", "--steps", "0", "--out", "v.mp4"], "positive"),
    (RENDER + ["--seed", "0", "--steps", BIG, "--out", "v.mp4"], "at most"),
    (RENDER + ["--seed", "0", "--out", "v.gif"], "mp4"),
    (RENDER + ["--seed", "0", "--out", "missing/v.mp4"], "does not exist"),
    (RENDER + ["--seed", "0", "--out", "a_file/v.mp4"], "a_file is not a folder"),
    (RENDER + ["--seed", "0", "--out", "folder.mp4"], "is a folder"),
    (RENDER + ["--seed", "0", "--out", "/proc/v.mp4"], "cannot write"),
    (RENDER + ["--seed", "0", "--compare", "bogus", "--out", "v.mp4"], "bad --compare"),
    (RENDER + ["--seed", "0", "--compare", "bump=grip,grip", "--out", "v.mp4"], "itself"),
    (RENDER + ["--seed", "0", "--compare", "bump=grip,stop", "--set", "bump=slide",
               "--out", "v.mp4"], "also given with --set"),
    (RENDER + ["--seed", "0", "--compare", "condition", "--out", "v.mp4"], "drop --condition"),
    (["render", "--robot", "two_wheel", "--seed", "0", "--out", "v.mp4"], "--condition is required"),
    (RENDER + ["--seed", "0", "--path", "dotted", "--out", "v.mp4"], "dotted"),
    # bench
    (["bench", "--steps", "0"], "positive"),
    (["bench", "--steps", "abc"], "not an integer"),
    (["bench", "--steps", BIG], "at most 1,000,000"),
    (["bench", "--blocks", "0"], "positive"),
    (["bench", "--blocks", "nan"], "not an integer"),
    (["bench", "--blocks", "99999999"], "at most 1,000"),
    (["bench", "--robot", "tricycle"], "tricycle"),
    (["bench", "--what"], "unrecognized arguments"),
    (["check", "--robot", "tricycle"], "tricycle"),
    (["check", "--actions", "0"], "positive"),
    (["run", "--robot", "my_robot.xml"], "no robot file"),
    (["run", "--robot", ROBOT_FILE], "needs a drive"),
    (["run", "--robot", ROBOT_FILE, "--drive", "hover"], "hover"),
    (["run", "--robot", "two_wheel", "--drive", "floating"], "has the two_wheel drive"),
    (["render", "--robot", "two_wheel,floating", "--condition", "avoidance", "--seed", "0",
      "--out", "v.mp4"], "one robot"),
    # demo and the command itself
    (["demo", "--out", "a_file"], "not a folder"),
    (["demo", "--workers", "-1"], "positive"),
    ([], "required"),
    (["fly"], "invalid choice"),
]
if os.geteuid() != 0:  # root writes into a read-only folder regardless of its mode
    CASES.append((["run", "--out", "read_only/results"], "cannot write"))


def _sandbox(folder):
    folder.mkdir()
    (folder / "a_file").write_text("not a folder\n")
    (folder / "empty_dir").mkdir()
    (folder / "folder.mp4").mkdir()
    if os.geteuid() != 0:
        (folder / "read_only").mkdir(mode=0o555)
    return folder


def _snapshot(folder):
    return sorted((str(p.relative_to(folder)), p.is_dir(), p.stat().st_size, p.stat().st_mtime_ns)
                  for p in folder.rglob("*"))


def _env():
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(ROOT)] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]))
    for name in ("EBRL_TEST_FAIL", "EBRL_TEST_CRASH", "EBRL_TEST_DISK_FULL", "EBRL_TEST_DISK_FULL_AT"):
        env.pop(name, None)
    return env


def _run(args, cwd):
    """One case as a fresh `python -m experiments`: (process, seconds, before, after)."""
    before = _snapshot(cwd)
    started = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "experiments", *args], cwd=cwd, env=_env(),
                          capture_output=True, text=True, timeout=60)
    return proc, time.perf_counter() - started, before, _snapshot(cwd)


def _run_here(args, cwd):
    """One case in this process (ebrl_here): (process, seconds, before, after)."""
    before = _snapshot(cwd)
    started = time.perf_counter()
    proc = ebrl_here(*args, cwd=cwd)
    return proc, time.perf_counter() - started, before, _snapshot(cwd)


#: Cases that also run as a fresh `python -m experiments` (one per kind of failure: the
#: parser's, a value's check, a folder's check).
FRESH = (0, 7, 39)


@pytest.fixture(scope="module")
def outcomes(tmp_path_factory):
    """Every case's (process, seconds, sandbox before, sandbox after), in this process."""
    base = tmp_path_factory.mktemp("bad_inputs")
    return [_run_here(args, _sandbox(base / f"case_{i:03d}")) for i, (args, _) in enumerate(CASES)]


@pytest.fixture(scope="module")
def fresh_outcomes(tmp_path_factory):
    """FRESH's cases as fresh processes, each in a sandbox of its own."""
    base = tmp_path_factory.mktemp("bad_inputs_fresh")
    return {i: _run(CASES[i][0], _sandbox(base / f"case_{i:03d}")) for i in FRESH}


def test_enough_cases_across_the_subcommands():
    commands = [args[0] if args else "" for args, _ in CASES]
    assert len(CASES) >= 40
    for command in ("run", "sweep", "report", "render", "bench"):
        assert commands.count(command) >= 5, command


def _check(index, proc, seconds, before, after):
    args, message = CASES[index]
    assert proc.returncode == 2, (proc.returncode, proc.stderr)
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], proc.stderr
    assert lines[0].startswith("ebrl"), proc.stderr
    assert "Traceback" not in proc.stderr
    assert proc.stdout == ""
    assert seconds < LIMIT_S, seconds
    assert after == before  # nothing written, nothing touched


@pytest.mark.parametrize("index", range(len(CASES)),
                         ids=[" ".join(args) or "(nothing)" for args, _ in CASES])
def test_a_bad_input_fails_fast_in_one_line_writing_nothing(outcomes, index):
    _check(index, *outcomes[index])


@pytest.mark.slow
@pytest.mark.parametrize("index", FRESH, ids=[" ".join(CASES[i][0]) for i in FRESH])
def test_a_bad_input_to_a_fresh_command_is_the_same_line(outcomes, fresh_outcomes, index):
    """The whole way a user starts it (`python -m experiments`): the same one line as in
    process."""
    _check(index, *fresh_outcomes[index])
    assert fresh_outcomes[index][0].stderr == outcomes[index][0].stderr
