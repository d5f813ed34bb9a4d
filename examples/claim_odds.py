"""How often each Section 3.6 claim holds on a draw of 50 runs, from our run folders and
from the paper's own figures.

A claim that compares two means (a one-sided test of a shrink below 100%) or a count of runs can
hold on one set of 50 seeds and fail on the next. This pools the runs of the folders given,
draws `--draws` sets of `--seeds` seeds **with replacement** from the seeds every group has
(a bootstrap: each draw is a sample the size of one experiment from the runs we have, the
same seeds for every robot and condition), computes each draw's summary and claims exactly
as `ebrl report` does (`aggregate.summarize`, `report.claims`), and prints the share of draws
on which each of the ten claims holds. The learning claims (a shrink) are judged two ways:
by the one-sided z test of the log shrink below 0 (as `ebrl report` does,
`verdicts.claim_tests`) and by the point estimate below 100%; C5 and C6 also by the count
tests against the paper's (`verdicts.count_tests`: Fisher's exact test for C5, the rank test
for C6; the share of draws on which it does not show a difference).

    .venv/bin/python examples/claim_odds.py results --paper

`--paper` makes the same draws from the paper's own figures (`paper_runs`), so that one
sees how often the paper's own result passes our test: per run, a first trial F from a
gamma distribution with the paper's mean and sd; the later trials' mean length L from a
normal distribution whose mean and sd are set (`calibrate`) so that the steps per trial
(F + (G - 1) L) / G, with G = 1 + floor((budget - F) / L) the trials that fit in the
budget, has the paper's mean and sd. The first trial and the steps per trial are drawn
together, as a run makes them (steps per trial include the first trial). A first trial
past the budget is a run without a goal. C5's count is judged on these draws too.

**C6 has no model-based odds.** Its bar, 49 goals, is the paper's own sample minimum (its
worst of 50 runs), not a property of the paper's distribution: a model fitted to the
paper's means and sds puts the paper's own worst run in its tail (the normal model of the
later trials made 49 goals a 3% event), so its odds say more of the model than of the
paper. Without any model: if our runs and the paper's were drawn from one continuous
distribution, the smallest of all m + n runs is equally likely to be any of them, so our n
runs all stay at or above the paper's minimum of m runs with probability m / (m + n)
(`c6_exchangeable`): 50% for 50 against 50 (a little more with ties of whole goals), 33%
for 100 against 50. "Every run at 49 goals or more" is a coin flip for a perfect
replication: failing it shows nothing, and holding it shows little. What C6 can show is a
difference in the tail: the rank test of the runs below 49 goals (`verdicts.rank_below`:
the chance that k or more of ours fall below the least of the paper's 50 under one
distribution, C(n, k) / C(n + 50, k)) is C6's verdict.
"""
import argparse
import sys

import numpy as np

from experiments import paper
from experiments.outputs import report
from experiments.outputs.verdicts import ALPHA, count_tests
from experiments.running import aggregate, results
from tasks.robots import DRIVES, PAPER_ROBOTS, ROBOTS


def pooled(folders):
    """{(robot, condition, seed): run} over the folders; a seed in two folders is an error."""
    runs = {}
    for folder in folders:
        for key, run in results.load_runs(folder).items():
            if key in runs:
                raise SystemExit(f"error: {key} is in more than one folder")
            runs[key] = run
    return runs


def verdicts(summary, model=False):
    """{claim: holds} as `ebrl report` judges them, each learning claim (a shrink) also by its
    point estimate ("... (point estimate)"), C5 and C6 also by their count tests ("...
    (count test: not shown different)": Fisher's for C5, the rank test for C6). model: the
    summary is of runs drawn from a model of the paper's figures, so C6 (a bar at the
    paper's own sample minimum) is left out."""
    out = {claim: bool(ok) for claim, _, ok in report.claims(summary)
           if not (model and claim.startswith(tuple(f"{g['robot']} avoidance: every run"
                                                    for g in summary["groups"])))}
    for g in summary["groups"]:
        if g["shrink"] is not None and (g["drive"], g["condition"]) in paper.RESULTS:
            out[f"{g['robot']} {g['condition']}: learning shrinks trials (point estimate)"] = \
                g["shrink"] < 1.0
    for row in count_tests(summary):
        if model and row["claim"] == "C6":
            continue
        out[f"{row['claim']}: {row['robot']} {row['condition']}, runs below {row['bar']} goals "
            f"(count test: not shown different)"] = row["p"] >= ALPHA
    return out


def draw(runs, common, n_seeds, rng):
    """One draw of n_seeds seeds with replacement from common, the same for every group:
    the runs re-keyed 0..n_seeds - 1 (a seed drawn twice counts twice)."""
    chosen = rng.choice(common, n_seeds, replace=True)
    groups = sorted({(r, c) for r, c, _ in runs})
    return {(r, c, i): runs[(r, c, int(s))] for r, c in groups for i, s in enumerate(chosen)}


def odds(runs, n_seeds, draws, seed=0):
    """{claim: share of draws on which it holds}, and the seeds every group has."""
    groups = {(r, c) for r, c, _ in runs}
    common = sorted(set.intersection(*({s for r, c, s in runs if (r, c) == g} for g in groups)))
    if len(common) < n_seeds:
        raise SystemExit(f"error: only {len(common)} seeds are in every group; --seeds {n_seeds}")
    rng = np.random.default_rng(seed)
    held = {}
    for _ in range(draws):
        for claim, ok in verdicts(aggregate.summarize(draw(runs, common, n_seeds, rng))).items():
            held.setdefault(claim, []).append(ok)
    return {c: float(np.mean(v)) for c, v in held.items()}, len(common)


def c6_exchangeable(n_ours, n_paper=paper.SEEDS):
    """The chance that all n_ours runs stay at or above the smallest of the paper's n_paper
    when both are drawn from one continuous distribution: n_paper / (n_paper + n_ours)
    (the smallest of all the runs is equally likely to be any one of them). No model."""
    return n_paper / (n_paper + n_ours)


def _trials(first, later, budget):
    """(goals, steps per trial) of runs whose first trial is `first` and whose later trials
    each last `later` steps, within `budget` steps (0 goals where first > budget)."""
    reached = first <= budget
    goals = np.where(reached, 1 + np.floor((budget - np.minimum(first, budget)) / later), 0)
    per = np.where(reached, (first + (goals - 1) * later) / np.maximum(goals, 1), np.nan)
    return goals.astype(np.int64), per


def calibrate(drive, condition, samples=20_000, rounds=60, seed=1):
    """(mean, sd) of the later trials' length L such that the drawn runs' steps per trial
    have the paper's mean and sd (fixed-point iteration on one large sample)."""
    ref = paper.RESULTS[(drive, condition)]
    budget = DRIVES[drive].budget
    m, s = ref["first_trial_steps"]["mean"], ref["first_trial_steps"]["sd"]
    pm, ps = ref["steps_per_trial"]["mean"], ref["steps_per_trial"]["sd"]
    rng = np.random.default_rng(seed)
    k = (m / s) ** 2
    first = rng.gamma(k, m / k, samples)
    z = rng.standard_normal(samples)
    mu, sd = pm, ps
    for _ in range(rounds):
        _, per = _trials(first, np.clip(mu + sd * z, 1, None), budget)
        got_m, got_s = np.nanmean(per), np.nanstd(per)
        mu, sd = max(1.0, mu * pm / got_m), max(1e-6, sd * ps / max(got_s, 1e-9))
    return mu, sd


def paper_runs(n_seeds, rng, later):
    """{(robot, condition, seed): run} of one draw from the paper's figures for both paper
    robots (`later`: calibrate's (mean, sd) per (drive, condition))."""
    runs = {}
    for robot in PAPER_ROBOTS:
        drive = ROBOTS[robot].drive
        budget = DRIVES[drive].budget
        for condition in paper.CONDITIONS:
            ref = paper.RESULTS[(drive, condition)]
            m, s = ref["first_trial_steps"]["mean"], ref["first_trial_steps"]["sd"]
            k = (m / s) ** 2
            first = rng.gamma(k, m / k, n_seeds)
            mu, sd = later[(drive, condition)]
            goals, per = _trials(first, np.clip(rng.normal(mu, sd, n_seeds), 1, None), budget)
            for i in range(n_seeds):
                ok = goals[i] > 0
                runs[(robot, condition, i)] = {
                    "metrics": {"first_trial_steps": float(first[i]) if ok else None,
                                "steps_per_trial": float(per[i]) if ok else None,
                                "goals": int(goals[i])},
                    "parameters": {"steps": budget, "drive": drive}, "memory_decisions": 0}
    return runs


def paper_odds(n_seeds, draws, seed=0):
    """{claim: share of draws from the paper's figures on which it holds}."""
    later = {key: calibrate(*key) for key in paper.RESULTS}
    rng = np.random.default_rng(seed)
    held = {}
    for _ in range(draws):
        summary = aggregate.summarize(paper_runs(n_seeds, rng, later))
        for claim, ok in verdicts(summary, model=True).items():
            held.setdefault(claim, []).append(ok)
    return {c: float(np.mean(v)) for c, v in held.items()}


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("folders", nargs="*", help="run folders (ebrl run --out)")
    p.add_argument("--seeds", type=int, default=50,
                   help="seeds per draw, drawn with replacement (default 50)")
    p.add_argument("--draws", type=int, default=200, help="draws (default 200)")
    p.add_argument("--robot", default=",".join(PAPER_ROBOTS),
                   help="robots to pool (default: the paper's, " + ",".join(PAPER_ROBOTS) + ")")
    p.add_argument("--paper", action="store_true", help="also draw from the paper's figures")
    args = p.parse_args(argv)
    if not args.folders and not args.paper:
        p.error("give run folders, --paper, or both")
    shares, theirs, n = {}, {}, 0
    if args.folders:
        robots = args.robot.split(",")
        runs = {k: v for k, v in pooled(args.folders).items() if k[0] in robots}
        if not runs:
            raise SystemExit(f"error: no runs of {args.robot} in {', '.join(args.folders)}")
        shares, n = odds(runs, args.seeds, args.draws)
    if args.paper:
        theirs = paper_odds(args.seeds, args.draws)
    source = f"our runs ({n} seeds)" if args.folders else ""
    print(f"{args.draws} draws of {args.seeds} seeds; share of draws on which each claim holds:")
    print(f"| claim | {source or 'ours'} | the paper's figures |\n|---|---:|---:|")
    claims = list(dict.fromkeys(list(shares) + list(theirs)))
    goals = paper.TWO_WHEEL_GOALS["avoidance_min"]
    c6 = f"two_wheel avoidance: every run reaches at least {goals} goals (paper min {goals})"
    if args.paper and c6 not in claims:
        claims.insert(next((i for i, c in enumerate(claims) if c.startswith("floating")),
                           len(claims)), c6)
    for claim in claims:
        cells = [f"{d[claim]:.1%}" if claim in d else "" for d in (shares, theirs)]
        if args.paper and "avoidance: every run reaches at least" in claim:
            cells[1] = f"{c6_exchangeable(args.seeds):.1%} (no model: m / (m + n))"
        print(f"| {claim} | {cells[0]} | {cells[1]} |")


if __name__ == "__main__":
    sys.exit(main())
