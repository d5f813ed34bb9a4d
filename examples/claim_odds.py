"""How often each Section 3.6 claim holds on a draw of 50 seeds from run folders.

A claim that compares two means (a shrink's 95% interval below 100%, the fewest goals of
50 runs) can hold on one set of 50 seeds and fail on the next. This pools the runs of
the folders given (the protocol's seeds and the validation's, say), draws `--draws` sets
of `--seeds` seeds without replacement (the same seeds for every robot and condition),
computes each draw's summary and claims exactly as `ebrl report` does
(`results.summarize`, `report.claims`), and prints the share of draws on which each
claim holds.

    .venv/bin/python examples/claim_odds.py results results_validation

`--paper` adds, for each drive's learning claims, the same share for draws from the
paper's own figures: first trials from a gamma distribution with the paper's mean and sd,
steps per trial normal with the paper's mean and sd (independent, clipped at 1), so that
one can see how often the paper's own result would pass our test.
"""
import argparse
import sys

import numpy as np

from experiments import paper
from experiments.outputs import report
from experiments.running import results
from tasks.robots import PAPER_ROBOTS


def pooled(folders):
    """{(robot, condition, seed): run} over the folders; a seed in two folders is an error."""
    runs = {}
    for folder in folders:
        for key, run in results.load_runs(folder).items():
            if key in runs:
                raise SystemExit(f"error: {key} is in more than one folder")
            runs[key] = run
    return runs


def odds(runs, n_seeds, draws, seed=0):
    """{claim: share of draws on which it holds}, and the seeds every group has."""
    groups = {(r, c) for r, c, _ in runs}
    common = sorted(set.intersection(*({s for r, c, s in runs if (r, c) == g} for g in groups)))
    if len(common) < n_seeds:
        raise SystemExit(f"error: only {len(common)} seeds are in every group; --seeds {n_seeds}")
    rng = np.random.default_rng(seed)
    held = {}
    for _ in range(draws):
        chosen = set(rng.choice(common, n_seeds, replace=False).tolist())
        sub = {k: v for k, v in runs.items() if k[2] in chosen}
        for claim, _, ok in report.claims(results.summarize(sub)):
            held.setdefault(claim, []).append(bool(ok))
    return {c: float(np.mean(v)) for c, v in held.items()}, len(common)


def paper_odds(drive, n_seeds, draws, seed=0):
    """{condition: share of draws from the paper's figures whose shrink's interval lies
    below 100%} (results.summarize's bootstrap on made-up runs)."""
    rng = np.random.default_rng(seed)
    out = {}
    for condition in paper.CONDITIONS:
        ref = paper.RESULTS[(drive, condition)]
        m, s = ref["first_trial_steps"]["mean"], ref["first_trial_steps"]["sd"]
        pm, ps = ref["steps_per_trial"]["mean"], ref["steps_per_trial"]["sd"]
        k = (m / s) ** 2
        ok = []
        for _ in range(draws):
            first = rng.gamma(k, m / k, n_seeds)
            per = np.clip(rng.normal(pm, ps, n_seeds), 1, None)
            runs = {("r", condition, i): {"metrics": {"first_trial_steps": float(f),
                                                      "steps_per_trial": float(p), "goals": 1},
                                          "parameters": {"steps": 1, "drive": drive},
                                          "memory_decisions": 0}
                    for i, (f, p) in enumerate(zip(first, per))}
            (g,) = results.summarize(runs)["groups"]
            ok.append(g["shrink_ci95"][1] < 1.0)
        out[condition] = float(np.mean(ok))
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("folders", nargs="+", help="run folders (ebrl run --out)")
    p.add_argument("--seeds", type=int, default=50, help="seeds per draw (default 50)")
    p.add_argument("--draws", type=int, default=200, help="draws (default 200)")
    p.add_argument("--robot", default=",".join(PAPER_ROBOTS),
                   help="robots to pool (default: the paper's, " + ",".join(PAPER_ROBOTS) + ")")
    p.add_argument("--paper", action="store_true", help="also draw from the paper's figures")
    args = p.parse_args(argv)
    robots = args.robot.split(",")
    runs = {k: v for k, v in pooled(args.folders).items() if k[0] in robots}
    if not runs:
        raise SystemExit(f"error: no runs of {args.robot} in {', '.join(args.folders)}")
    shares, n = odds(runs, args.seeds, args.draws)
    print(f"{args.draws} draws of {args.seeds} seeds from the {n} seeds every group has:")
    for claim, share in shares.items():
        print(f"  {share:6.1%}  {claim}")
    if args.paper:
        drives = sorted({run["parameters"].get("drive") for run in runs.values()}
                        & {drive for drive, _ in paper.RESULTS})
        for drive in drives:
            for condition, share in paper_odds(drive, args.seeds, args.draws).items():
                print(f"  {share:6.1%}  the paper's own {drive} {condition} figures: "
                      "learning shrinks trials (interval below 100%)")


if __name__ == "__main__":
    sys.exit(main())
