"""Provenance in every summary, and no pooling of runs made under different protocols or
parameters (experiments.running.provenance), through the real command on real runs."""
import functools
import json
import pathlib

import pytest

import helpers
from experiments.running import provenance
from tasks.protocols import PROTOCOL_VERSION

ebrl = functools.partial(helpers.ebrl, check=True)
here = functools.partial(helpers.ebrl_here, check=True)  # the same command in this process
SHORT = ["--robot", "two_wheel", "--condition", "random", "--steps", "300", "--workers", "1",
         "--no-progress"]


def test_seed_ranges_and_the_digest():
    assert provenance.seed_ranges([7, 0, 1, 2, 5, 8, 2]) == "0-2,5,7-8"
    assert provenance.seed_ranges([9000]) == "9000"
    a = {"seed": 1, "agent": {"x": 1, "y": 2}, "steps": 300}
    b = {"steps": 300, "agent": {"y": 2, "x": 1}, "seed": 2}
    assert provenance.parameters_digest(a) == provenance.parameters_digest(b)
    assert provenance.parameters_digest(a) != provenance.parameters_digest(dict(a, steps=301))


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    out = tmp_path_factory.mktemp("prov") / "results"
    here("run", *SHORT, "--seeds", "0-1", "--out", out)
    return out


def test_summary_and_report_name_protocol_commit_seeds_and_parameters(made):
    summary = json.loads((made / "summary.json").read_text())
    prov = summary["provenance"]
    assert prov["protocol_versions"] == [PROTOCOL_VERSION]
    config = json.loads((made / "two_wheel/random/seed_000/config.json").read_text())
    commit = config["versions"]["git_commit"]
    assert prov["commits"] == [commit] and len(commit.removesuffix("+dirty")) == 40
    assert prov["clean"] is (not commit.endswith("+dirty"))
    (group,) = prov["groups"]
    run = json.loads((made / "two_wheel/random/seed_001/run.json").read_text())
    assert group == {"robot": "two_wheel", "condition": "random",
                     "protocol_version": PROTOCOL_VERSION, "seeds": "0-1",
                     "parameters_sha256": provenance.parameters_digest(run["parameters"]),
                     "commits": [commit]}
    report = (made / "REPORT.md").read_text()
    assert f"Protocol version {PROTOCOL_VERSION}; commit `{commit}`" in report
    # the figures' tests beside it (experiments.outputs.verdicts), in both files
    tests = summary["tests"]
    assert tests["margin"] == [2 / 3, 1.5] and tests["alpha"] == 0.05
    assert [r["figure"] for r in tests["figures"]] == ["first-trial steps", "steps per trial"]
    assert "## The figures tested against the paper" in report
    assert "| two_wheel | random | first-trial steps | 6,087 (5,789, 49) |" in report
    assert f"| two_wheel | random | {PROTOCOL_VERSION} | 0-1 | `{group['parameters_sha256']}` |" \
        in report


def test_report_refuses_to_pool_other_parameters_in_one_line(made, tmp_path):
    import shutil
    out = tmp_path / "results"
    shutil.copytree(made, out)
    before = (out / "summary.json").read_bytes()
    proc = here("run", *SHORT, "--seeds", "2", "--set", "policy_threshold=0.1", "--out", out,
                check=False)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in proc.stderr
    assert "two_wheel/random: seeds 0 and 2" in lines[0]
    assert "different parameters (agent.policy_threshold)" in lines[0]
    assert (out / "two_wheel/random/seed_002/run.json").exists()  # the run is kept
    assert (out / "summary.json").read_bytes() == before  # no summary of the mix
    proc = here("report", out, check=False)
    assert proc.returncode == 2 and len(proc.stderr.strip().splitlines()) == 1


def test_report_refuses_to_pool_other_protocol_versions(made, tmp_path):
    import shutil
    out = tmp_path / "results"
    shutil.copytree(made, out)
    path = out / "two_wheel/random/seed_001/run.json"
    run = json.loads(path.read_text())
    run["parameters"]["protocol_version"] = PROTOCOL_VERSION - 1  # an older run
    path.write_text(json.dumps(run))
    proc = here("report", out, check=False)
    assert proc.returncode == 2
    assert proc.stderr.strip() == (
        f"ebrl: error: two_wheel/random: seeds 0 and 1 were made under different protocol "
        f"versions: {PROTOCOL_VERSION} and {PROTOCOL_VERSION - 1}; not pooled "
        "into one group: one results folder per protocol and setting (another --out), or "
        "remove the stale runs")
    assert pathlib.Path(out / "summary.json").read_bytes() == (made / "summary.json").read_bytes()
