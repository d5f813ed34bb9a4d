"""Bad input on the newest surfaces (issue 58), each exit status 2 and one line naming the
file or the option, nothing written and nothing lost: a multiverse folder's damaged
bench.json (named, moved aside, made again), its damaged record shard (refused, left as
it is) and a refused resume (found before any work, nothing touched);
learners' sizes no machine holds (bounded before any run, the largest that fits named);
mount `rest` values; behaviour genomes (with a property test of the genome reader);
`ebrl evolve/fit --storage` on a file that is not a database; `ebrl bench --robot FILE`.
Commands run in this process (helpers.ebrl_here) on real files; a multiverse folder's
runs are written without running (tests/run_folders.py)."""
import functools
import hashlib
import json
import os
import pathlib
import shutil
import types

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import run_folders
from ebrl import behaviour as genomes
from ebrl.baselines import mfec, qtable
from experiments.checks import validate
from experiments.running import results, schema
from experiments.studies import multiverse
from helpers import ROOT, ebrl_here

EXAMPLES = int(os.environ.get("EBRL_PROPERTY_EXAMPLES", "200"))
MANY = settings(max_examples=EXAMPLES, deadline=None, database=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture])


def _refused(proc, *said):
    assert proc.returncode == 2, (proc.returncode, proc.stdout, proc.stderr)
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("ebrl"), proc.stderr
    assert all(s in lines[0] for s in said), lines[0]
    assert "Traceback" not in proc.stderr
    return lines[0]


def _tree(folder):
    return {p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(pathlib.Path(folder).rglob("*")) if p.is_file()}


# -- a multiverse folder -------------------------------------------------------------
MV = ["--factors", "threshold", "--universes", "1", "--seeds", "0-1", "--workers", "1",
      "--no-progress"]
STEPS = run_folders.STEPS


@pytest.fixture(scope="module")
def reported_universe(tmp_path_factory):
    """A multiverse folder whose every run is on disk (written, not run), reported once
    (which records them: OUT/records)."""
    out = tmp_path_factory.mktemp("universe") / "mv"
    _, chosen = multiverse.universes(multiverse.select(["threshold"]), 1)
    for s in multiverse.plan(chosen, [0, 1], STEPS):
        results.write_run(multiverse.root_of(out, s), s, run_folders.result((20, 45), s.steps),
                          {"lock": "test"})
    ebrl_here("multiverse", *MV, "--steps", STEPS, "--out", out, check=True)
    return out


@pytest.fixture
def universe(tmp_path, reported_universe):
    """A copy of the reported multiverse folder, for one test to damage."""
    out = tmp_path / "mv"
    shutil.copytree(reported_universe, out)
    return out


BOOKKEEPING = [  # (damaged bench.json, what the warning says)
    (b"[1, 2]", "bench.json: it holds a list, not an object of robots"),
    (b'{"two_wheel": {"fused_loop": 80}}', "bench.json: floating is missing"),
    (b"\xff", "bench.json is not JSON (UnicodeDecodeError)"),
]


@pytest.mark.parametrize("content, said", BOOKKEEPING, ids=[c[1][:36] for c in BOOKKEEPING])
def test_a_damaged_bench_json_is_named_moved_aside_and_made_again(universe, content, said):
    name = "bench.json"
    (universe / name).write_bytes(content)
    records = _tree(universe / "records")
    proc = ebrl_here("multiverse", *MV, "--steps", STEPS, "--out", universe)
    assert proc.returncode == 0 and "Traceback" not in proc.stderr, proc.stderr
    warnings = proc.stderr.strip().splitlines()
    assert len(warnings) == 1 and warnings[0].startswith("ebrl: warning: ")
    assert f"{universe / name}" in warnings[0] and said in warnings[0], warnings[0]
    aside = list(universe.glob(f"{name}.damaged-*"))
    assert len(aside) == 1 and aside[0].read_bytes() == content  # kept, never deleted
    assert aside[0].name in warnings[0]
    assert not (universe / name).exists()  # made again by --bench; no floor without it
    assert _tree(universe / "records") == records  # every run recorded: none made
    assert (universe / "MULTIVERSE.md").exists()


@pytest.mark.parametrize("damage", ["cut short", "not gzip"])
def test_a_damaged_record_shard_is_refused_and_left_as_it_is(universe, damage):
    """The records' own defect (issue 57's refusal, kept): never moved aside or made
    again, since its runs are what the study is."""
    (shard,) = (universe / "records").glob("*.jsonl.gz")
    data = shard.read_bytes()
    shard.write_bytes(data[:-9] if damage == "cut short" else b"{not json\n")
    before = _tree(universe)
    proc = ebrl_here("multiverse", *MV, "--steps", STEPS, "--out", universe)
    _refused(proc, f"{shard}: damaged record file")
    assert _tree(universe) == before


def _dead_session(folder, steps):
    """An open shard of a session whose machine died (a header, no run), of steps."""
    from experiments.studies import multiverse_records as kept
    folder.mkdir()
    header = {"format": kept.FORMAT, "version": kept.VERSION, "session": "dead",
              "identity": kept.identity(multiverse.select(["threshold"]), steps),
              "host": "a machine that died", "pid": 0, "workers": 1, "backend": "local"}
    (folder / "dead-01.open.jsonl").write_text(json.dumps(header) + "\n")


@pytest.mark.parametrize("records", ["OUT/records", "another folder"])
def test_a_refused_resume_touches_nothing(universe, tmp_path, records):
    """Another --steps: refused by the records of the first (OUT/records), or, with the
    records elsewhere, by the run folders, before any work: no run, no record, and not
    even a dead session's open shard sealed."""
    extra = []
    if records == "another folder":
        _dead_session(tmp_path / "elsewhere", STEPS + 10)
        extra = ["--records", tmp_path / "elsewhere"]
    before = _tree(universe), _tree(tmp_path / "elsewhere")
    proc = ebrl_here("multiverse", *MV, "--steps", STEPS + 10, "--out", universe, *extra)
    if records == "OUT/records":
        _refused(proc, f"{universe / 'records'}", f"--steps {STEPS}, this call asks for "
                 f"--steps {STEPS + 10}")
    else:
        _refused(proc, "holds a run made with other parameters",
                 f"steps: {STEPS} on disk, {STEPS + 10} asked")
    assert (_tree(universe), _tree(tmp_path / "elsewhere")) == before


# -- learners' sizes -------------------------------------------------------------------
SIZES = [  # (agent, --set, option named)
    ("mfec", "action_levels=1000000000000000", "action_levels"),
    ("mfec", "neighbours=1000000000000", "neighbours"),
    ("qtable", "action_levels=1000000000000000", "action_levels"),
    ("qtable", f"action_levels={10**400}", "action_levels"),
]


@pytest.mark.parametrize("agent, setting, option", SIZES, ids=[f"{a} {s[:24]}" for a, s, _ in SIZES])
def test_a_size_no_machine_holds_is_refused_before_any_run(tmp_path, agent, setting, option):
    out = tmp_path / "out"
    proc = ebrl_here("run", "--agent", agent, "--set", setting, "--seeds", "0", "--steps", "5",
                     "--out", out)
    line = _refused(proc, f"--set {option}=", "of memory available",
                    f"the largest {option} that fits is ")
    assert "--workers" not in line and not out.exists()
    largest = int(line.rsplit(" ", 1)[1].replace(",", ""))
    assert largest >= (2 if option == "action_levels" else 1)


@pytest.mark.parametrize("module, sizes", [(qtable, {"action_levels": 2}),
                                           (mfec, {"memory_size": 1, "neighbours": 1,
                                                   "action_levels": 2})])
@given(available=st.integers(10**3, 10**13), given_value=st.integers(2, 10**18),
       steps=st.integers(1, 10**6), dims=st.tuples(st.integers(1, 12), st.integers(1, 3)))
@settings(max_examples=100, deadline=None, database=None)
def test_the_largest_size_named_is_the_largest_that_fits(module, sizes, available, given_value,
                                                          steps, dims):
    """validate._largest: the value it names fits in the memory given, one more does not
    (or it is the value given); a size's estimate grows with it."""
    config = (qtable.QTableConfig() if module is qtable else mfec.MFECConfig())

    def estimate(c):
        return module.memory_bytes(c, *dims, steps)
    for name, low in sizes.items():
        largest = validate._largest(estimate, config, name, low, given_value, available)
        fields = {f: getattr(config, f) for f in config.__dataclass_fields__}

        def at(v):
            return estimate(types.SimpleNamespace(**{**fields, name: v}))
        if largest is None:
            assert at(low) > available
            continue
        assert low <= largest <= given_value and at(largest) <= available
        assert largest == given_value or at(largest + 1) > available


def test_a_size_fits_to_the_byte():
    config = mfec.MFECConfig()
    validate.memory_fits("mfec", config, (7, 1), 30_000, {"neighbours": 11}, "two_wheel",
                         available=10**9)
    with pytest.raises(ValueError, match=r"--set neighbours=11: .* the largest neighbours "
                                         r"that fits is"):
        validate.memory_fits("mfec", config, (7, 1), 30_000, {"neighbours": 11}, "two_wheel",
                             available=mfec.memory_bytes(config, 7, 1, 30_000) - 1)


# -- mount rest values -----------------------------------------------------------------
POINT = (ROOT / "models" / "mounts" / "point.toml").read_text()
GYM_ANT = (ROOT / "models" / "mounts" / "gym_ant.toml").read_text()
RESTS = [  # (mount text, the line's field and words)
    (POINT.replace("[bumper]", "[rest]\nrot = 1e20\n\n[bumper]"),
     "rest.rot: joint 'rot' has no limits; its rest must be within [-6.283, 6.283] rad"),
    (POINT.replace("[bumper]", "[rest]\nballx = -1e20\n\n[bumper]"),
     "rest.ballx: joint 'ballx' has no limits; its rest must be within [-1000, 1000] m"),
    (POINT.replace("[bumper]", f"[rest]\nrot = {10**400}\n\n[bumper]"),
     "rest.rot: must be a finite number, got an integer of 401 digits"),
    (GYM_ANT.replace("hip_1 = 0.0", f"hip_1 = {10**400}"),
     "rest.hip_1: must be a finite number, got an integer of 401 digits"),
    (GYM_ANT.replace("hip_1 = 0.0", "hip_1 = 1" + "0" * 5000),
     "not a TOML file: Exceeds the limit (4300 digits)"),
    (GYM_ANT.replace("unit = 0.4", f"unit = {10**400}"),
     "unit: must be a finite number, got an integer of 401 digits"),
]


@pytest.mark.parametrize("text, said", RESTS, ids=[r[1][:30] for r in RESTS])
def test_a_mount_rest_value_is_one_line_naming_the_file_and_the_field(tmp_path, text, said):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    out = tmp_path / "out"
    proc = ebrl_here("run", "--robot", path, "--seeds", "0", "--steps", "5", "--out", out)
    _refused(proc, f"{path.name}: {said}")
    assert not out.exists()


# -- behaviour genomes -----------------------------------------------------------------
PAPER_EQ8 = json.loads((ROOT / "behaviours" / "paper_eq8.json").read_text())
GENOMES = [  # (file bytes, what the line says after the file's name)
    (json.dumps({**PAPER_EQ8, "behaviour": ["eq8"]}).encode(), "field behaviour: ['eq8']; valid"),
    (json.dumps({**PAPER_EQ8, "behaviour": {"eq8": 1}}).encode(), "field behaviour: {'eq8': 1}"),
    (json.dumps({**PAPER_EQ8, "bias": 10**400}).encode(),
     "field bias: not a finite number (an integer of 401 digits)"),
    (json.dumps({**PAPER_EQ8, "weights": [10**309] * 7}).encode(),
     "field weights[0]: not a finite number (an integer of 310 digits)"),
    (json.dumps(PAPER_EQ8).replace('"bias": 0.0', f'"bias": {"9" * 5000}').encode(),
     "not JSON (an integer of more than 4300 digits)"),
    (b"[" * 100_000 + b"]" * 100_000, "not JSON"),
    (b"\xff\xfe{}", "not JSON (not UTF-8 text)"),
]


@pytest.mark.parametrize("content, said", GENOMES, ids=[g[1][:30] for g in GENOMES])
@pytest.mark.parametrize("command", ["run", "evolve"])
def test_a_bad_genome_is_one_line_naming_the_file(tmp_path, command, content, said):
    path = tmp_path / "genome.json"
    path.write_bytes(content)
    out = tmp_path / "out"
    option = "--behaviour" if command == "run" else "--start"
    proc = ebrl_here(command, "--robot", "two_wheel", option, path, "--out", out)
    _refused(proc, f"behaviour file {path}: {said}")
    assert not out.exists() and path.read_bytes() == content


JSON = st.recursive(st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=5),
                    lambda inner: st.lists(inner, max_size=4)
                    | st.dictionaries(st.text(max_size=5), inner, max_size=4), max_leaves=12)


def _near_genome(draw_value, key, base):
    return {**base, key: draw_value}


@MANY
@given(st.sampled_from(["eq8", "eq9-10"]), st.sampled_from(sorted(PAPER_EQ8)), JSON,
       st.integers(-10**600, 10**600))
def test_the_genome_reader_gives_a_genome_or_its_one_line(family, key, value, big):
    base = json.loads((ROOT / "behaviours" / f"paper_{family}.json").read_text())
    for data in (value, _near_genome(value, key, base), _near_genome(big, key, base),
                 {**base, "behaviour": value}):
        try:
            genome = genomes.from_dict(data)
        except genomes.GenomeError as e:
            assert str(e) and "\n" not in str(e)
        else:
            assert genomes.from_dict(genomes.to_dict(genome)) == genome


@MANY
@given(st.binary(max_size=300))
def test_the_genome_file_reader_gives_a_genome_or_its_one_line_naming_the_file(
        tmp_path_factory, data):
    path = tmp_path_factory.mktemp("genome") / "g.json"
    path.write_bytes(data)
    try:
        genomes.load(path)
    except genomes.GenomeError as e:
        assert str(e).startswith(f"behaviour file {path}: ") and "\n" not in str(e)


# -- study storage ---------------------------------------------------------------------
STORAGES = [  # (the file's bytes, what the line says)
    (b"my notes, not a database\n", "not an SQLite database"),
    (b"SQLite format 3\x00" + b"garbage" * 100, "cannot open the study storage"),
]


@pytest.mark.parametrize("content, said", STORAGES, ids=["not sqlite", "damaged sqlite"])
@pytest.mark.parametrize("command", [["evolve", "--robot", "two_wheel"], ["fit"]],
                         ids=["evolve", "fit"])
def test_a_storage_that_is_not_a_database_leaves_nothing_behind(tmp_path, command, content,
                                                                 said):
    keep = tmp_path / "mine"
    keep.mkdir()
    db = keep / "notes.db"
    db.write_bytes(content)
    out = tmp_path / "out"
    proc = ebrl_here(*command, "--storage", db, "--out", out)
    _refused(proc, said)
    assert not out.exists() and sorted(p.name for p in keep.iterdir()) == ["notes.db"]
    assert db.read_bytes() == content


# -- ebrl bench --robot ----------------------------------------------------------------
@pytest.mark.parametrize("args, said", [
    (["--robot", "no/such/robot.xml", "--drive", "two_wheel"], "no robot file at no/such/robot.xml"),
    (["--robot", ROOT / "models" / "two_wheel.xml"], "needs a drive: one of two_wheel, floating"),
    (["--robot", "two_wheel", "--drive", "hover"], "hover"),
])
def test_bench_refuses_a_robot_as_run_does(tmp_path, args, said):
    _refused(ebrl_here("bench", *args, cwd=tmp_path), said)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_bench_times_a_robot_file_with_its_drive(tmp_path):
    proc = ebrl_here("bench", "--robot", ROOT / "models" / "two_wheel.xml", "--drive",
                     "two_wheel", "--steps", "5", "--blocks", "1", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    row = proc.stdout.strip().splitlines()[-1].split()
    assert row[0].endswith("two_wheel.xml") and all(
        float(x) == float(x) for x in row[1:-2])  # numbers, not NaN, up to the fused loop's


# the helpers the tests above share, checked once
def test_schema_readers_name_the_file(tmp_path):
    path = tmp_path / "bench.json"
    check = functools.partial(schema.check_bench, robots=("two_wheel",))
    path.write_text('{"two_wheel": {"fused_loop": 80}}')
    assert schema.read_json(path, check) == {"two_wheel": {"fused_loop": 80}}
    path.write_text("[3]")
    with pytest.raises(schema.Damaged, match=rf"^{path}: it holds a list, not an object of "
                                             "robots$"):
        schema.read_json(path, check)
    path.write_text('{"two_wheel": {"fused_loop": NaN}}')  # bench writes NaN where not fused
    assert schema.read_json(path, check)["two_wheel"]["fused_loop"] != 0
