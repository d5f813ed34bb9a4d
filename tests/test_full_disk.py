"""A full disk at every writer: each ends in one line naming the folder, keeps what was
there, and the same command finishes once the disk is freed (the report files, FIT.md,
EVOLVE.md, a video, a killed writer's temporary file). Split from test_faults.py, whose
commands and hooks it shares."""
import os
import pathlib
import subprocess
import sys

import pytest

from experiments.running import results
from test_faults import FIT, ebrl, env, here, leftovers

#: The slow tier (pyproject.toml's markers): processes starved of disk.
pytestmark = pytest.mark.slow


# -- every writer: a full disk is one line naming the folder, what was there kept --------
def snapshot(folder):
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(pathlib.Path(folder).rglob("*"))
            if p.is_file()}


@pytest.fixture(scope="module")
def reported(tmp_path_factory):
    """A tiny run folder with its report, a RESULTS.md beside it and a study's FIT.md."""
    root = tmp_path_factory.mktemp("reported")
    out = root / "results"
    here("run", "--robot", "two_wheel", "--condition", "all", "--seeds", "0", "--steps",
         "300", "--workers", "2", "--no-progress", "--out", out)
    (root / "RESULTS.md").write_text("# R\n\nkept above\n")
    here("report", out, "--results", root / "RESULTS.md", "--figures", root / "figures")
    here(*FIT[:2], "2", *FIT[3:], "--out", root / "fit")
    return root


def full_disk_line(status, err, folder):
    lines = err.strip().splitlines()
    assert status == 2 and len(lines) == 1 and "Traceback" not in err, err
    assert "No space left on device" in lines[0] and f" in {folder}:" in lines[0], lines[0]
    return lines[0]


def test_a_full_disk_at_each_report_file_is_one_line_and_keeps_the_last(reported,
                                                                        monkeypatch, capsys):
    """`ebrl report --results` (in this process: the disk fills at each of its files in
    turn, the figures, summary.json, REPORT.md, RESULTS.md): one line naming the folder,
    every file as it was; freed, the same command finishes."""
    from experiments import cli
    from experiments.running import disk
    root = reported
    before = snapshot(root)
    args = ["report", str(root / "results"), "--results", str(root / "RESULTS.md"),
            "--figures", str(root / "figures")]
    for pattern, folder in (("traces_two_wheel.png", root / "results" / "figures"),
                            ("summary.json", root / "results"),
                            ("REPORT.md", root / "results"), ("RESULTS.md", root)):
        monkeypatch.setenv(results.TEST_DISK_FULL_AT, pattern)
        monkeypatch.setattr(disk, "_full", False)  # the atomic write's
        capsys.readouterr()
        status = cli.main(args)
        full_disk_line(status, capsys.readouterr().err, folder)
        assert snapshot(root) == before and leftovers(root) == [], pattern
    monkeypatch.delenv(results.TEST_DISK_FULL_AT)
    monkeypatch.setattr(disk, "_full", False)  # the atomic write's
    assert cli.main(args) == 0 and snapshot(root) == before


def test_a_full_disk_at_fit_md_is_one_line_and_the_same_command_finishes(reported, tmp_path):
    import shutil
    out = tmp_path / "fit"
    shutil.copytree(reported / "fit", out)
    (out / "FIT.md").write_text("an older FIT.md\n")
    args = [*FIT[:2], "2", *FIT[3:], "--out", out]
    proc = ebrl(*args, env=env(EBRL_TEST_DISK_FULL_AT="FIT.md"), check=False)
    full_disk_line(proc.returncode, proc.stderr, out)
    assert (out / "FIT.md").read_text() == "an older FIT.md\n" and leftovers(out) == []
    proc = here(*args)
    assert "0 trials made now, 2 in the study" in proc.stdout
    assert (out / "FIT.md").read_text() == (reported / "fit" / "FIT.md").read_text()


def test_a_full_disk_at_evolve_md_is_one_line_and_keeps_the_last(reported, tmp_path):
    out, figures = tmp_path / "EVOLVE.md", tmp_path / "figures"
    (tmp_path / "none").mkdir()  # no studies, no evolved runs: their lines say so
    args = ["evolve-report", "--evolve", tmp_path / "none", "--hand", reported / "results",
            "--evolved", tmp_path / "none", "--out", out, "--figures", figures]
    here(*args)
    before = out.read_bytes()
    out.write_bytes(before + b"\nan older page\n")
    proc = ebrl(*args, env=env(EBRL_TEST_DISK_FULL_AT="EVOLVE.md"), check=False)
    full_disk_line(proc.returncode, proc.stderr, tmp_path)
    assert out.read_bytes() == before + b"\nan older page\n" and leftovers(tmp_path) == []


def test_a_full_disk_at_a_video_is_one_line_and_keeps_the_last(tmp_path):
    from experiments.outputs import rendering
    try:
        rendering.ensure_backend()
    except rendering.RenderingError as e:
        pytest.skip(str(e))
    video = tmp_path / "v.mp4"
    video.write_bytes(b"an older video")
    args = ["render", "--robot", "two_wheel", "--condition", "avoidance", "--seed", "0",
            "--steps", "40", "--out", video]
    proc = ebrl(*args, env=env(EBRL_TEST_DISK_FULL_AT="v.mp4"), check=False)
    full_disk_line(proc.returncode, proc.stderr, tmp_path)
    assert video.read_bytes() == b"an older video" and leftovers(tmp_path) == []
    here(*args)
    assert video.stat().st_size > 1000


def test_a_killed_writers_temporary_file_is_removed_by_the_next_write(tmp_path):
    """SIGKILL mid-write leaves `.run.json.<host>.<pid>.*.tmp`: the next write of the file
    removes it when that pid no longer runs; a live writer's, or another host's, stays."""
    path = tmp_path / "run.json"
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    alive = os.getppid()  # pytest's parent: running while this test runs
    left = tmp_path / f"{results.tmp_prefix(path, dead.pid)}abc.tmp"
    live = tmp_path / f"{results.tmp_prefix(path, alive)}def.tmp"
    other = tmp_path / f".run.json.another-host.{dead.pid}.ghi.tmp"
    for f in (left, live, other):
        f.write_text("half")
    results.atomic_write(path, "{}")
    assert path.read_text() == "{}"
    assert not left.exists() and live.exists() and other.exists()
