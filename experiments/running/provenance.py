"""Where a summary's runs came from: the protocol version, the commit (and whether its tree
was clean), the seeds and a digest of the runs' parameters, per group and over all
(summary.json's "provenance", REPORT.md's first lines); and the refusal to pool into one
group runs made under different protocols or parameters (`check`).

A run's parameters (run.json, execution.RunSpec.parameters) are everything that decides its
result; two runs of one group may differ in their seed alone. The commit is config.json's
(`results.versions`: "+dirty" after it when the tree had uncommitted changes to tracked
files); a run made at another commit under the same parameters computes the same bits
(a change that alters them bumps the protocol version), so commits are listed, not checked.
"""
import hashlib
import json
import pathlib

from experiments.running import results

DIRTY = "+dirty"


class MixedRuns(results.ResultsError):
    """Runs of one group made under different protocols or parameters."""


def parameters_digest(parameters):
    """sha256 (16 hex digits) of a run's parameters less its seed, as canonical JSON."""
    rest = {k: v for k, v in parameters.items() if k != "seed"}
    text = json.dumps(rest, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def seed_ranges(seeds):
    """Seeds as ranges, e.g. [0, 1, 2, 5, 7, 8] -> "0-2,5,7-8"."""
    seeds = sorted(set(int(s) for s in seeds))
    parts, i = [], 0
    while i < len(seeds):
        j = i
        while j + 1 < len(seeds) and seeds[j + 1] == seeds[j] + 1:
            j += 1
        parts.append(str(seeds[i]) if i == j else f"{seeds[i]}-{seeds[j]}")
        i = j + 1
    return ",".join(parts)


def _commit(root, key):
    """config.json's git commit of the run at key (robot, condition, seed) under root;
    "unknown" when the file or the entry is missing."""
    robot, condition, seed = key
    path = pathlib.Path(root) / robot / condition / f"seed_{seed:03d}" / "config.json"
    try:
        return json.loads(path.read_text()).get("versions", {}).get("git_commit") or "unknown"
    except (OSError, ValueError):
        return "unknown"


def _differs(a, b, skip=("seed",)):
    """(dotted name, a's value, b's value) of the first parameter in which two runs'
    parameters differ, the seed aside (into nested dicts: "agent.policy_threshold"); None
    when they agree."""
    for k in sorted((set(a) | set(b)) - set(skip)):
        x, y = a.get(k), b.get(k)
        if isinstance(x, dict) and isinstance(y, dict):
            inner = _differs(x, y, ())
            if inner is not None:
                return (f"{k}.{inner[0]}",) + inner[1:]
        elif x != y:
            return k, x, y
    return None


def check(runs):
    """MixedRuns (one line) when a group's runs (same robot label and condition) differ in
    protocol version or any parameter but the seed: such runs are never pooled."""
    first = {}
    for (robot, condition, seed), run in sorted(runs.items()):
        p = run["parameters"]
        if (robot, condition) not in first:
            first[(robot, condition)] = (seed, p)
            continue
        seed0, p0 = first[(robot, condition)]
        diff = _differs(p0, p)
        if diff is None:
            continue
        key, x, y = diff
        what = "protocol versions" if key == "protocol_version" else f"parameters ({key})"
        raise MixedRuns(f"{robot}/{condition}: seeds {seed0} and {seed} were made under different "
                        f"{what}: {x!r} and {y!r}; not pooled into one group: one results folder "
                        "per protocol and setting (another --out), or remove the stale runs")


def of(runs, root):
    """summary.json's "provenance": {"protocol_versions", "commits", "clean", "groups":
    [{"robot", "condition", "protocol_version", "parameters_sha256", "seeds", "commits"}]}.
    Calls check first (MixedRuns)."""
    check(runs)
    groups, commits = [], set()
    for robot, condition in sorted({(r, c) for r, c, _ in runs}):
        keys = sorted(k for k in runs if k[:2] == (robot, condition))
        mine = sorted({_commit(root, k) for k in keys})
        commits |= set(mine)
        p = runs[keys[0]]["parameters"]
        groups.append({"robot": robot, "condition": condition,
                       "protocol_version": p.get("protocol_version"),
                       "parameters_sha256": parameters_digest(p),
                       "seeds": seed_ranges(k[2] for k in keys), "commits": mine})
    return {"protocol_versions": sorted({g["protocol_version"] for g in groups},
                                        key=lambda v: (v is None, v)),
            "commits": sorted(commits),
            "clean": all(c != "unknown" and not c.endswith(DIRTY) for c in commits),
            "groups": groups}


def lines(prov):
    """REPORT.md's provenance lines (markdown)."""
    versions = ", ".join(str(v) for v in prov["protocol_versions"])
    commits = ", ".join(f"`{c}`" for c in prov["commits"])
    out = [f"Protocol version {versions}; commit {commits} "
           f"({'clean tree' if prov['clean'] else 'NOT a clean tree'}).", "",
           "| robot | condition | protocol | seeds | parameters (sha256) |",
           "|---|---|---:|---|---|"]
    for g in prov["groups"]:
        out.append(f"| {g['robot']} | {g['condition']} | {g['protocol_version']} | {g['seeds']} "
                   f"| `{g['parameters_sha256']}` |")
    return out + [""]
