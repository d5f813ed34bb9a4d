"""A soak of the runner's fault handling (a benchmark, not a test):

    python -m experiments.ops.soak [--seeds 0-127] [--steps 200] [--workers 2] [--every 3-8]

`ebrl run` on the paper's robots, both conditions and the given seeds (512 short runs by
default) while a worker process, picked at random among those past their start (1.5 s
of CPU: running runs), is killed (SIGKILL, as the out-of-memory killer does) every few
seconds; the same command again, without kills,
until it exits 0 (each pass retries the runs whose worker died twice); then the same set
clean in another folder. It prints the figures and exits 1 unless both folders hold every
run and the same summary.json, trials and traces.
"""
import argparse
import json
import os
import pathlib
import random
import signal
import subprocess
import sys
import tempfile
import time

from experiments import ROOT
from experiments.ops import procs



def _workers_of(pid, min_cpu):
    """The live pool workers of the command at pid (procs.pool_workers) that have used at
    least min_cpu seconds of CPU (past loading their kernels: running runs)."""
    return [w for w in procs.pool_workers(pid) if (procs.cpu_seconds(w) or 0) >= min_cpu]


def _command(args, out):
    return [sys.executable, "-m", "experiments", "run", "--robot", "paper", "--condition",
            "all", "--seeds", args.seeds, "--steps", str(args.steps), "--workers",
            str(args.workers), "--no-progress", "--out", str(out)]


def _killed_pass(args, out, rng):
    """One `ebrl run` with a random worker killed every args.every seconds; returns (exit
    status, kills, last stderr line)."""
    proc = subprocess.Popen(_command(args, out), cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    kills = 0
    lo, hi = args.every
    next_kill = time.monotonic() + rng.uniform(lo, hi)
    started = shown = time.monotonic()
    while proc.poll() is None:
        time.sleep(0.05)
        if time.monotonic() - shown >= 30:
            shown = time.monotonic()
            print(f"  {shown - started:.0f} s: {len(list(out.glob('*/*/seed_*/run.json')))} "
                  f"runs written, {kills} workers killed", flush=True)
        if time.monotonic() < next_kill:
            continue
        workers = _workers_of(proc.pid, args.min_cpu)
        if not workers:  # none past its start yet: the kill waits for one
            continue
        try:
            os.kill(rng.choice(workers), signal.SIGKILL)
            kills += 1
        except ProcessLookupError:
            pass
        next_kill = time.monotonic() + rng.uniform(lo, hi)
    _, err = proc.communicate()
    return proc.returncode, kills, (err.strip().splitlines() or [""])[-1]


def _runs(out):
    """run folder -> (status, trials.csv, trace.npz bytes) for every run.json under out."""
    got = {}
    for path in sorted(pathlib.Path(out).glob("*/*/seed_*/run.json")):
        status = json.loads(path.read_text())["status"]
        files = [path.parent / n for n in ("trials.csv", "trace.npz")]
        got[str(path.parent.relative_to(out))] = (status, *[
            f.read_bytes() if f.exists() else None for f in files])
    return got


def main(argv=None):
    p = argparse.ArgumentParser(prog="python -m experiments.ops.soak", description=__doc__.split(
        "\n\n")[0])
    p.add_argument("--seeds", default="0-127", help="seeds per robot and condition")
    p.add_argument("--steps", type=int, default=200)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--every", default="3-8", help="seconds between kills, LO-HI (uniform)")
    p.add_argument("--min-cpu", type=float, default=1.5,
                   help="kill only workers past their start: this much CPU used (s)")
    p.add_argument("--rng", type=int, default=0, help="seed of the kills' timing and target")
    p.add_argument("--out", type=pathlib.Path, default=None,
                   help="folder for the two result sets (default: a temporary one)")
    args = p.parse_args(argv)
    args.every = tuple(float(x) for x in args.every.split("-"))
    out = args.out or pathlib.Path(tempfile.mkdtemp(prefix="ebrl_soak_"))
    out.mkdir(parents=True, exist_ok=True)
    rng = random.Random(args.rng)

    started = time.monotonic()
    passes, kills = [], 0
    while True:
        status, k, last = _killed_pass(args, out / "killed", rng)
        kills += k
        failed = sum(1 for s, *_ in _runs(out / "killed").values() if s == "failed")
        passes.append((status, k, failed))
        print(f"pass {len(passes)} with kills: exit {status}, {k} workers killed, "
              f"{failed} runs recorded failed", flush=True)
        if status == 0:
            break
        if status != 1 or len(passes) >= 20:
            print(f"soak: stopped: {last}", file=sys.stderr)
            return 1
    killed_s = time.monotonic() - started
    started = time.monotonic()
    clean = subprocess.run(_command(args, out / "clean"), cwd=ROOT, capture_output=True,
                           text=True)
    clean_s = time.monotonic() - started
    if clean.returncode != 0:
        print(f"soak: the clean set failed: {clean.stderr.strip()}", file=sys.stderr)
        return 1
    a, b = _runs(out / "killed"), _runs(out / "clean")
    complete = sum(1 for s, *_ in a.values() if s == "complete")
    same_summary = ((out / "killed" / "summary.json").read_bytes()
                    == (out / "clean" / "summary.json").read_bytes())
    print(f"runs: {len(b)} clean, {complete} complete after the kills ({len(a)} folders); "
          f"workers killed: {kills} in {len(passes)} passes ({killed_s:.0f} s); "
          f"the clean set: {clean_s:.0f} s; runs recorded failed after the first pass: "
          f"{passes[0][2]}; summary.json identical: {same_summary}; trials and traces "
          f"identical: {a == b}; results under {out}")
    return 0 if same_summary and a == b and complete == len(b) else 1


if __name__ == "__main__":
    sys.exit(main())
