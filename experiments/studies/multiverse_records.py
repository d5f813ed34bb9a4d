"""`ebrl multiverse`'s records: what each finished run leaves, compact, so that the study
outlives the machine it ran on (a fresh clone resumes it, or reports it, from them).

A records folder (`--records`; by default OUT/records; the committed study's is
docs/data/multiverse/) holds shards, each a file of JSON lines. A session appends the
runs it finishes to its open shard, `<session>-<n>.open.jsonl`, a line each, flushed to
disk as it is written; the shard is sealed (gzip, `<session>-<n>.jsonl.gz`, written
once, never rewritten, so appends never rewrite a big file and git keeps each once)
when it holds SHARD_RUNS runs and when the session ends, and by the next session when
a machine died under it (seal_left). A run killed mid-line leaves an unfinished last
line, which is dropped (the run is made again); any other line that cannot be read
makes the file damaged: one line, before any work, and nothing is touched.

A shard's first line is its header: FORMAT and VERSION, the identity of its design
(identity: the protocol's version, the runs' steps, the factors and the design; a
records folder holds one design's runs), the factors' levels when it was written, the
commit and the packages that made its runs (results.versions), its session, host and
process. Each other line is a run (record_of):

    {"setting": the digest of its overrides (its folder's name, multiverse.folder_key),
     "robot", "condition", "seed", "steps",
     "digest": the sha256 of its parameters (16 hex digits: what a rerun matches on),
     "goals", "trials": each completed trial's steps, in order,
     "memory_decisions", "seconds" (its compute), "at" (seconds into its session)}

and a sealed session's last line is {"end": ...}: its wall time, runs made, workers,
backend, and whether it was stopped. A run is what the analysis and a resume need: its
trials (every figure: the first trial, steps per trial both ways, the shrink, the
goals) and its digest; no traces (100-350 bytes a run gzipped: docs/data/multiverse/
README.md).
"""
import gzip
import hashlib
import json
import os
import pathlib
import re
import secrets
import socket
import time
import zlib

from experiments.running import results
from experiments.studies import multiverse
from tasks.protocols import PROTOCOL_VERSION

FORMAT = "ebrl-multiverse-records"
VERSION = 1
#: Runs a shard holds before it is sealed and the next opened.
SHARD_RUNS = 1000
_SEALED, _OPEN = ".jsonl.gz", ".open.jsonl"
_HEX = re.compile(r"^[0-9a-f]+$")


class RecordsError(results.ResultsError):
    """A records folder that cannot be used as asked: one line naming the file."""


def identity(chosen, steps):
    """What the records of one study share, and a records folder must hold one of: the
    protocol's version, the runs' steps (None: the paper's budgets), the factors and the
    chosen ones, and the design over them (its generators and universes)."""
    d = multiverse.design_for(chosen)
    return {"protocol_version": PROTOCOL_VERSION, "steps": steps,
            "factors": [f.key for f in multiverse.factors()],
            "chosen": [f.key for f in chosen], "design": d.name(),
            "generators": list(d.generators)}


def _budgets(steps):
    return "the paper's budgets" if steps is None else f"--steps {steps}"


def _other(theirs, ours):
    """What differs between a shard's identity and this call's, in words; None if
    nothing."""
    if theirs.get("protocol_version") != ours["protocol_version"]:
        return (f"runs of protocol {theirs.get('protocol_version')}, this code's is "
                f"{ours['protocol_version']}")
    if theirs.get("steps") != ours["steps"]:
        return (f"runs made with {_budgets(theirs.get('steps'))}, this call asks for "
                f"{_budgets(ours['steps'])}")
    for key in ("factors", "chosen", "design", "generators"):
        if theirs.get(key) != ours[key]:
            return (f"another design ({key}: {theirs.get(key)}, this call's: {ours[key]})")
    return None


def digest(spec):
    """The sha256 of a run's parameters (execution.RunSpec.parameters: everything that
    determines its result), 16 hex digits."""
    text = json.dumps(spec.parameters(), sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def key(spec):
    """A run's key among the records: (setting, robot, condition, seed, steps)."""
    return (multiverse.folder_key(spec.overrides), spec.label, spec.condition, spec.seed,
            spec.steps)


def record_of(spec, trial_ends, memory_decisions, seconds, at=0.0):
    """A finished run's record (the module docstring)."""
    import numpy as np
    ends = np.asarray(trial_ends, dtype=np.int64)
    trials = np.diff(np.concatenate([[0], ends])).tolist()
    setting, robot, condition, seed, steps = key(spec)
    return {"setting": setting, "robot": robot, "condition": condition, "seed": seed,
            "steps": steps, "digest": digest(spec), "goals": len(trials), "trials": trials,
            "memory_decisions": int(memory_decisions), "seconds": round(float(seconds), 3),
            "at": round(float(at), 1)}


def from_folder(root, spec, run):
    """The record of a complete run folder (its run.json's record run, checked by
    results.read_run), from its trials.csv: a run made before records were kept, or
    whose record a kill stopped."""
    import csv
    folder = results.run_dir(root, spec)
    with open(folder / "trials.csv", newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["reached"] == "1"]
    return record_of(spec, [int(r["cumulative_steps"]) for r in rows],
                     run["memory_decisions"], run.get("seconds", 0.0))


def _check_record(r):
    """A record line's reason to be refused, or None."""
    fields = {"setting": str, "robot": str, "condition": str, "seed": int, "steps": int,
              "digest": str, "goals": int, "trials": list, "memory_decisions": int,
              "seconds": (int, float), "at": (int, float)}
    for name, kind in fields.items():
        if not isinstance(r.get(name), kind) or isinstance(r.get(name), bool):
            return f"its {name!r} is missing or not a {getattr(kind, '__name__', 'number')}"
    if not (_HEX.match(r["setting"]) and _HEX.match(r["digest"])):
        return "its setting or digest is not hexadecimal"
    if any(not isinstance(n, int) or isinstance(n, bool) or n < 1 for n in r["trials"]):
        return "a trial is not a positive whole number of steps"
    if r["goals"] != len(r["trials"]) or sum(r["trials"]) > r["steps"]:
        return "its goals or trials do not agree with its steps"
    return None


def _damaged(path, reason):
    return RecordsError(f"{path}: damaged record file: {reason}; restore it (git checkout) "
                        "or move it out of the records folder")


def read_shard(path):
    """(header, records, end) of a shard; for an open one, an unfinished last line (a
    run killed while its line was written) dropped with a warning. RecordsError when it
    cannot be read."""
    path = pathlib.Path(path)
    try:
        data = path.read_bytes()
        if path.name.endswith(_SEALED):
            data = gzip.decompress(data)
        text = data.decode()
    except (OSError, EOFError, ValueError, zlib.error) as e:  # cut short, altered, not text
        raise _damaged(path, f"it cannot be read ({type(e).__name__})") from None
    lines = text.split("\n")
    if lines[-1]:  # no newline after the last line
        if path.name.endswith(_SEALED):
            raise _damaged(path, "its last line is cut short")
        results.warn(f"{path}: an unfinished last line dropped (its run is made again)")
    lines = lines[:-1]
    parsed = []
    for number, line in enumerate(lines, 1):
        try:
            parsed.append(json.loads(line))
        except ValueError:
            raise _damaged(path, f"line {number} is not JSON") from None
        if not isinstance(parsed[-1], dict):
            raise _damaged(path, f"line {number} is not a record")
    if not parsed:
        return None, [], None
    header = parsed[0]
    if header.get("format") != FORMAT or header.get("version") != VERSION:
        raise _damaged(path, f"its first line is not a header of {FORMAT} version {VERSION}")
    end = parsed[-1].get("end") if len(parsed) > 1 and "end" in parsed[-1] else None
    body = parsed[1:-1] if end is not None else parsed[1:]
    for number, record in enumerate(body, 2):
        reason = _check_record(record)
        if reason:
            raise _damaged(path, f"line {number}: {reason}")
    return header, body, end


def shards(folder):
    """The shard files of a records folder, sealed and open, in name order (their
    sessions' order); none for a folder that does not exist."""
    folder = pathlib.Path(folder)
    if not folder.is_dir():
        return []
    return sorted(p for p in folder.iterdir() if p.is_file()
                  and (p.name.endswith(_SEALED) or p.name.endswith(_OPEN)))


class Store:
    """A records folder read and checked against this call's identity: runs (key ->
    record), the shards' headers and ends by file, and the sessions (session -> its
    header, end and records' last "at")."""

    def __init__(self, folder, ident):
        self.folder, self.ident = pathlib.Path(folder), ident
        self.runs, self.files, self.sessions, self.file_keys = {}, {}, {}, {}
        where = {}
        for path in shards(self.folder):
            header, body, end = read_shard(path)
            if header is None:
                continue
            other = _other(header.get("identity", {}), ident)
            if other:
                raise RecordsError(f"{path} holds {other}; use another --records folder")
            self.files[path] = (header, len(body), end)
            session = self.sessions.setdefault(header.get("session", path.name),
                                               {"header": header, "end": None, "at": 0.0,
                                                "runs": 0})
            self.file_keys[path] = set()
            session["end"] = end or session["end"]
            session["runs"] += len(body)
            for record in body:
                session["at"] = max(session["at"], record["at"])
                k = (record["setting"], record["robot"], record["condition"], record["seed"],
                     record["steps"])
                if k in self.runs and (self.runs[k]["digest"], self.runs[k]["trials"]) != \
                        (record["digest"], record["trials"]):
                    raise RecordsError(
                        f"{path} and {where[k]} disagree on the run {record['robot']}/"
                        f"{record['condition']}/seed {record['seed']} of setting "
                        f"{record['setting']}: keep the one to trust in the folder")
                self.runs.setdefault(k, record)
                where.setdefault(k, path)
                self.file_keys[path].add(k)

    def match(self, specs):
        """{spec: record} of the specs with a record; RecordsError when a record holds
        the same run made with other parameters (the code changed what a run computes
        without a new protocol version)."""
        out = {}
        for spec in specs:
            record = self.runs.get(key(spec))
            if record is None:
                continue
            if record["digest"] != digest(spec):
                raise RecordsError(
                    f"{self.folder}: the record of {spec.label}/{spec.condition}/seed "
                    f"{spec.seed} (setting {key(spec)[0]}) was made with other parameters "
                    "than this code's; use another --records folder")
            out[spec] = record
        return out

    def timing(self, keys=None):
        """Each session that made runs (of keys: runs by key(spec), where given): {"started",
        "seconds", "runs_made", "workers", "backend", "interrupted"} (a session whose
        machine died: the seconds to its last record)."""
        used = {h.get("session", path.name) for path, h in self._files_of(keys)}
        out = []
        for name, s in sorted(self.sessions.items()):
            if name not in used:
                continue
            h, end = s["header"], s["end"]
            out.append({"session": name, "started": h.get("started"),
                        "seconds": end["seconds"] if end else s["at"],
                        "runs_made": end["runs_made"] if end else s["runs"],
                        "workers": h.get("workers") or 1, "backend": h.get("backend"),
                        "interrupted": bool(end["interrupted"]) if end else True})
        return out

    def commits(self, keys=None):
        """The commits that made the shards' runs (of keys, where given)."""
        return sorted({h.get("versions", {}).get("git_commit", "unknown")
                       for _, h in self._files_of(keys)})

    def _files_of(self, keys):
        """(path, header) of each shard holding runs of keys (every shard: keys None)."""
        return [(path, h) for path, (h, _, _) in self.files.items()
                if keys is None or self.file_keys[path] & keys]


def _alive(header):
    """Whether the open shard's writer is a live process on this host."""
    if header.get("host") != socket.gethostname():
        return False
    try:
        os.kill(int(header.get("pid", 0)), 0)
    except (OSError, ValueError):
        return False
    return int(header.get("pid", 0)) > 0


def _seal(path, end=None):
    """Writes the open shard at path as its sealed, gzipped self (with end as its last
    line, if given) and removes the open one; an unfinished last line is dropped."""
    text = path.read_text()
    if not text.endswith("\n"):
        text = text[:text.rfind("\n") + 1]
    if not text:
        path.unlink()
        return None
    if end is not None:
        text += json.dumps({"end": end}, sort_keys=True) + "\n"
    sealed = path.with_name(path.name[: -len(_OPEN)] + _SEALED)
    results.atomic_write(sealed, gzip.compress(text.encode(), compresslevel=9, mtime=0))
    path.unlink()
    return sealed


def seal_left(folder):
    """Seals the open shards that sessions left (their machine died or was stopped),
    the runs they hold kept; a live session's on this host is left to it."""
    for path in shards(folder):
        if path.name.endswith(_OPEN):
            header, _, _ = read_shard(path)
            if header is None or not _alive(header):
                _seal(path)


class Writer:
    """A session's records, appended to its open shard (opened at its first run) and
    sealed every SHARD_RUNS runs and by close."""

    def __init__(self, folder, ident, levels, workers, backend):
        self.folder, self.ident, self.levels = pathlib.Path(folder), ident, levels
        self.workers, self.backend = workers, backend
        self.clock = time.perf_counter()
        stamp = time.strftime("%Y%m%dT%H%M%SZ", time.gmtime())
        self.session = f"{stamp}-{secrets.token_hex(3)}"
        self.started = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
        self.part, self.count, self.in_shard = 0, 0, 0
        self.file, self.path, self.versions = None, None, None

    def _open(self):
        self.folder.mkdir(parents=True, exist_ok=True)
        self.versions = self.versions or results.versions()
        self.part += 1
        self.path = self.folder / f"{self.session}-{self.part:02d}{_OPEN}"
        self.file, self.in_shard = open(self.path, "a"), 0
        self._line({"format": FORMAT, "version": VERSION, "identity": self.ident,
                    "levels": self.levels, "versions": self.versions,
                    "session": self.session, "started": self.started,
                    "host": socket.gethostname(), "pid": os.getpid(),
                    "workers": self.workers, "backend": self.backend})

    def _line(self, obj):
        self.file.write(json.dumps(obj, sort_keys=True) + "\n")
        self.file.flush()
        os.fsync(self.file.fileno())

    def at(self):
        return time.perf_counter() - self.clock

    def add(self, record):
        """Appends a run's record, to a new shard when the open one is full (that one
        sealed)."""
        if self.file is not None and self.in_shard >= SHARD_RUNS:
            self.file.close()
            _seal(self.path)
            self.file = None
        if self.file is None:
            self._open()
        self._line(record)
        self.count += 1
        self.in_shard += 1

    def close(self, runs_made, interrupted=False):
        """Seals the open shard with the session's end; a session that wrote no run
        leaves nothing."""
        if self.file is None:
            return
        self.file.close()
        _seal(self.path, {"seconds": round(self.at(), 1), "runs_made": runs_made,
                          "workers": self.workers, "backend": self.backend,
                          "interrupted": interrupted, "records": self.count})
        self.file = None
