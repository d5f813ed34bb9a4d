"""`ebrl multiverse`'s records (experiments.studies.multiverse_records): what a run leaves,
read back as written; an open shard sealed, its unfinished last line dropped; a damaged
file, records of another design or steps, two records that disagree, refused in one line
before any work with nothing touched; and (slow, in this process: ebrl_here) a tiny
design resumed in a new folder from another's records, no run made twice, the same table
bit for bit, the report made from the records alone, the literal and the current
universes the protocols' own runs."""
import gzip
import json
import shutil

import pytest

from experiments.running import execution
from experiments.studies import multiverse
from experiments.studies import multiverse_records as records
from helpers import ebrl_here
from tasks.robots import PAPER_ROBOTS


def _ident(steps=300):
    return records.identity(multiverse.select(["threshold", "body", "exploration"]), steps)


def _spec(seed, steps=300):
    return execution.RunSpec("two_wheel", "avoidance", seed, steps)


def _write(folder, seeds, ident=None, close=True):
    writer = records.Writer(folder, ident or _ident(), {}, 2, "local")
    for seed in seeds:
        writer.add(records.record_of(_spec(seed), [120, 200, 290], 17, 1.5, writer.at()))
    if close:
        writer.close(len(seeds))
    return writer


def _snapshot(folder):
    return {p.name: p.read_bytes() for p in folder.iterdir()}


def test_records_are_read_back_as_written(tmp_path, monkeypatch):
    monkeypatch.setattr(records, "SHARD_RUNS", 2)
    _write(tmp_path, [0, 1, 2])
    names = sorted(p.name for p in tmp_path.iterdir())
    assert len(names) == 2 and all(n.endswith(".jsonl.gz") for n in names)  # sealed at 2
    store = records.Store(tmp_path, _ident())
    assert store.match([_spec(s) for s in range(4)]).keys() == {_spec(s) for s in range(3)}
    record = store.runs[records.key(_spec(1))]
    assert record["trials"] == [120, 80, 90] and record["goals"] == 3
    assert record["digest"] == records.digest(_spec(1))
    (session,) = store.timing()
    assert session["runs_made"] == 3 and not session["interrupted"]
    header, body, end = records.read_shard(tmp_path / names[-1])
    assert header["identity"] == _ident() and len(body) == 1 and end["records"] == 3
    # a shard is written once: sealing the same lines again gives the same bytes
    again = gzip.compress(gzip.decompress((tmp_path / names[0]).read_bytes()), 9, mtime=0)
    assert again == (tmp_path / names[0]).read_bytes()


def test_an_open_shard_is_read_and_sealed_its_unfinished_line_dropped(tmp_path, capsys,
                                                                        monkeypatch):
    writer = _write(tmp_path, [0, 1], close=False)
    with open(writer.path, "a") as f:  # a run killed while its line was written
        f.write('{"setting": "abc", "rob')
    writer.file.close()
    store = records.Store(tmp_path, _ident())
    assert len(store.runs) == 2 and store.timing()[0]["interrupted"]
    assert "unfinished last line dropped" in capsys.readouterr().err
    header, _, _ = records.read_shard(writer.path)
    assert records._alive(header)  # its writer, this process, lives: left to it
    records.seal_left(tmp_path)
    assert writer.path.exists()
    monkeypatch.setattr(records, "_alive", lambda header: False)  # its machine died
    records.seal_left(tmp_path)
    (sealed,) = tmp_path.iterdir()
    assert sealed.name.endswith(".jsonl.gz") and len(records.Store(tmp_path, _ident()).runs) == 2


@pytest.mark.parametrize("damage", ["cut", "garbage", "bad line", "bad record"])
def test_a_damaged_record_file_is_refused(tmp_path, damage):
    _write(tmp_path, [0, 1])
    (path,) = tmp_path.iterdir()
    data = path.read_bytes()
    lines = gzip.decompress(data).decode().splitlines(keepends=True)
    if damage == "cut":
        path.write_bytes(data[: len(data) // 2])
    elif damage == "garbage":
        path.write_bytes(b"not a gzip file")
    elif damage == "bad line":
        path.write_bytes(gzip.compress("".join(lines[:2] + ["{oops\n"] + lines[2:]).encode()))
    else:
        record = json.loads(lines[1])
        record["trials"] = [-5]
        path.write_bytes(gzip.compress("".join([lines[0], json.dumps(record) + "\n"]).encode()))
    with pytest.raises(records.RecordsError, match="damaged record file"):
        records.Store(tmp_path, _ident())


def test_records_of_another_design_or_steps_and_records_that_disagree(tmp_path):
    _write(tmp_path / "a", [0])
    with pytest.raises(records.RecordsError, match="--steps 300, this call asks for --steps 400"):
        records.Store(tmp_path / "a", _ident(400))
    other = records.identity(multiverse.select(["threshold", "body"]), 300)
    with pytest.raises(records.RecordsError, match="another design"):
        records.Store(tmp_path / "a", other)
    # the same run twice with other trials (another machine's bits)
    _write(tmp_path / "a", [0])
    store = records.Store(tmp_path / "a", _ident())
    assert len(store.runs) == 1
    writer = records.Writer(tmp_path / "a", _ident(), {}, 1, "local")
    writer.add(records.record_of(_spec(0), [100], 17, 1.5))
    writer.close(1)
    with pytest.raises(records.RecordsError, match="disagree"):
        records.Store(tmp_path / "a", _ident())
    # a record of this run made with other parameters (the code changed, not the version)
    for path in (tmp_path / "a").iterdir():
        path.unlink()
    writer = records.Writer(tmp_path / "a", _ident(), {}, 1, "local")
    writer.add(dict(records.record_of(_spec(0), [100], 17, 1.5), digest="0" * 16))
    writer.close(1)
    with pytest.raises(records.RecordsError, match="made with other parameters"):
        records.Store(tmp_path / "a", _ident()).match([_spec(0)])


TINY = ["--seeds", "0-1", "--steps", "1500", "--workers", "2", "--no-progress"]


@pytest.mark.parametrize("bad", ["damaged", "steps"])
def test_bad_records_stop_the_command_before_any_work(tmp_path, bad):
    folder = tmp_path / "records"
    _write(folder, [0], ident=records.identity(multiverse.factors(), 1500))
    (path,) = folder.iterdir()
    if bad == "damaged":
        path.write_bytes(path.read_bytes()[:-9])
    before = _snapshot(folder)
    steps = ["--steps", "1500"] if bad == "damaged" else ["--steps", "1200"]
    proc = ebrl_here("multiverse", "--universes", "1", "--seeds", "0-1", *steps,
                     "--records", folder, "--out", tmp_path / "out")
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1, proc.stderr
    assert ("damaged record file" if bad == "damaged" else "--steps 1500") in lines[0]
    assert _snapshot(folder) == before and not (tmp_path / "out").exists()


@pytest.mark.slow
def test_a_study_resumes_from_its_records_on_a_fresh_folder(tmp_path):
    whole, part, fresh = tmp_path / "whole", tmp_path / "part", tmp_path / "fresh"
    assert ebrl_here("multiverse", "--universes", "2", *TINY, "--out", whole).returncode == 0
    table = (whole / "multiverse.csv").read_bytes()
    runs = sorted(whole.glob("runs/*/*/*/seed_*/run.json"))
    # another machine made the first universe; its records alone come here
    assert ebrl_here("multiverse", "--universes", "1", *TINY, "--out", part).returncode == 0
    shutil.copytree(part / "records", fresh / "records")
    done = len(list(part.glob("runs/*/*/*/seed_*/run.json")))
    proc = ebrl_here("multiverse", "--universes", "2", *TINY, "--out", fresh)
    assert proc.returncode == 0, proc.stderr
    assert (fresh / "multiverse.csv").read_bytes() == table  # bit for bit
    made = list(fresh.glob("runs/*/*/*/seed_*/run.json"))  # no recorded run made again
    assert len(made) == len(runs) - done and 0 < done < len(runs)
    ident = records.identity(multiverse.factors(), 1500)
    store = records.Store(fresh / "records", ident)
    assert len(store.runs) == len(runs) and [s["runs_made"] for s in store.timing()] == \
        [done, len(runs) - done]
    # a report counts the sessions and commits that made its runs, not others' in the folder
    started = min(h["started"] for h, _, _ in store.files.values())
    first = set().union(*(store.file_keys[p] for p, (h, _, _) in store.files.items()
                          if h["started"] == started))
    assert [s["runs_made"] for s in store.timing(first)] == [done]
    assert store.timing(set()) == [] and store.commits(set()) == []
    assert store.commits(first) == store.commits()
    # a rerun makes nothing and writes no shard
    shards = sorted((fresh / "records").iterdir())
    assert ebrl_here("multiverse", "--universes", "2", *TINY, "--out", fresh).returncode == 0
    assert sorted((fresh / "records").iterdir()) == shards
    # run folders without records (made before records were kept, or killed between the
    # two) give their records: no run made
    shutil.rmtree(whole / "records")
    assert ebrl_here("multiverse", "--universes", "2", *TINY, "--out", whole).returncode == 0
    rebuilt = records.Store(whole / "records", ident)
    def made(record):  # what a run made, not when or in how long
        return {k: v for k, v in record.items() if k not in ("at", "seconds")}

    assert {k: made(r) for k, r in rebuilt.runs.items()} == \
        {k: made(r) for k, r in store.runs.items()}
    assert [s["runs_made"] for s in rebuilt.timing()] == [0]
    assert (whole / "multiverse.csv").read_bytes() == table
    # the report from the records alone (a fresh clone's committed records), no run made
    # and as a page's section (--results): the user's text around it kept byte for byte
    page = tmp_path / "page" / "RESULTS.md"
    page.parent.mkdir()
    page.write_bytes(b"# Mine\r\n\nkept \xc3\xa9\n")
    proc = ebrl_here("multiverse", "--universes", "2", "--seeds", "0-1", "--steps", "1500",
                     "--report-only", "--records", fresh / "records", "--out", tmp_path / "r",
                     "--results", page, "--figures", tmp_path / "page" / "figs")
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "r" / "multiverse.csv").read_bytes() == table
    assert not (tmp_path / "r" / "runs").exists()
    report = (tmp_path / "r" / "MULTIVERSE.md").read_text()
    assert "literal protocol" in report and "## Cost" in report and "2 call(s)" in report
    text = page.read_bytes().decode("utf-8")
    assert text.startswith("# Mine\r\n\nkept \u00e9\n")
    block = text[text.index("<!-- ebrl multiverse: generated"):].replace("\r\n", "\n")
    assert block.rstrip().endswith("<!-- ebrl multiverse: end -->")
    assert "\n## How much the conclusions depend on the open details\n" in block
    assert "\n### Cost\n" in block and "\n# " not in block
    curves = sorted(p.name for p in (tmp_path / "r" / "figures").glob("spec_*.png"))
    assert curves and sorted(p.name for p in (tmp_path / "page" / "figs").iterdir()) == \
        [f"multiverse_{name}" for name in curves]
    assert all(f"](figs/multiverse_{name})" in block for name in curves)
    # the first universe is the literal protocol's runs, the current one `ebrl run`'s, bit
    # for bit
    d, universes = multiverse.universes(multiverse.factors(), 3)
    for universe, protocol in ((universes[0], "literal"), (universes[-1], "adopted")):
        assert ebrl_here("run", "--protocol", protocol, "--seeds", "0-1", "--steps", "1500",
                         "--workers", "2", "--no-progress", "--out", tmp_path / protocol,
                         check=True).returncode == 0
        for robot in PAPER_ROBOTS:
            for condition in ("random", "avoidance"):
                root = multiverse.root_of(whole, execution.RunSpec(
                    robot, condition, 0, 1500, universe.overrides(robot, condition)))
                for seed in ("seed_000", "seed_001"):
                    mine = root / robot / condition / seed / "trace.npz"
                    theirs = tmp_path / protocol / robot / condition / seed / "trace.npz"
                    assert mine.read_bytes() == theirs.read_bytes(), (protocol, mine)
