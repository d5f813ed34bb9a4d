"""Section 3.6's figures tested against the paper's mean, sd and n (issue 48).

For each of the eight figures the paper gives with a mean, an sd and a number of runs (the
first trial and the steps per trial, both robots, both conditions), two tests of our runs
against the paper's, both Welch's (unequal variances), both by scipy from the two samples'
summaries (`scipy.stats.ttest_ind_from_stats`):

- **difference** (`welch`): two-sided, H0 that our mean is the paper's;
- **equivalence** (`tost`): two one-sided tests of H0 that our mean lies outside
  [LOW, HIGH] times the paper's, each against the paper's sample scaled by that bound (a
  sample of k X has mean k m and sd k s, so its Welch test is the test of mu_ours = k
  mu_paper with the paper's own sampling error); p = the larger of the two. The margin
  is docs/interpretation.md's, "Testing the figures", chosen before protocol 7's runs.

A figure's verdict (`verdict`): "equivalent" when the TOST p < ALPHA; else "different"
when Welch's p < ALPHA; else "undecided" (neither shown). The four shrinks are a ratio of
two of these means with no sd of their own: ours with its percentile bootstrap interval
(results.summarize) beside the paper's point. C5 and C6 are counts of runs: Fisher's exact
test (`fisher`, two-sided) of ours against the paper's 43 of 50 runs below 30 goals and 0
of 50 below 49. "Within 1.5x" (ours / paper between 2/3 and 1.5, the point alone) stays as
a column, for continuity with the earlier protocols' tables; it is not a verdict.
"""
import math

from scipy import stats

from experiments import paper

ALPHA = 0.05
#: The equivalence margin, as ratios of our mean to the paper's (docs/interpretation.md,
#: "Testing the figures").
LOW, HIGH = 2.0 / 3.0, 1.5
#: The figures with a paper mean, sd and n (experiments.paper.RESULTS' keys).
FIGURES = (("first_trial_steps", "first-trial steps"), ("steps_per_trial", "steps per trial"))


def welch_df(s1, n1, s2, n2):
    """Welch-Satterthwaite degrees of freedom of two samples' sds and sizes."""
    a, b = s1 * s1 / n1, s2 * s2 / n2
    return (a + b) ** 2 / (a * a / (n1 - 1) + b * b / (n2 - 1))


def welch(m1, s1, n1, m2, s2, n2, alternative="two-sided"):
    """Welch's t test of sample 1 against sample 2 from their means, sds (ddof 1) and
    sizes: {"t", "df", "p"} (scipy.stats.ttest_ind_from_stats, equal_var=False)."""
    r = stats.ttest_ind_from_stats(m1, s1, n1, m2, s2, n2, equal_var=False,
                                   alternative=alternative)
    return {"t": float(r.statistic), "df": float(welch_df(s1, n1, s2, n2)),
            "p": float(r.pvalue)}


def tost(m1, s1, n1, m2, s2, n2, low=LOW, high=HIGH):
    """Equivalence of sample 1's mean to between low and high times sample 2's: two
    one-sided Welch tests, H0 mu1 <= low mu2 (against sample 2 scaled by low) and H0 mu1
    >= high mu2 (scaled by high). {"lower", "upper" (each test's p), "p" (the larger)}."""
    lower = welch(m1, s1, n1, low * m2, low * s2, n2, alternative="greater")["p"]
    upper = welch(m1, s1, n1, high * m2, high * s2, n2, alternative="less")["p"]
    return {"lower": lower, "upper": upper, "p": max(lower, upper)}


def power(m, s, n_ours, n_paper, low=LOW, high=HIGH, alpha=ALPHA):
    """The TOST's power (normal approximation) when our runs are drawn exactly as the
    paper's (the same mean m and sd s), n_ours of ours against the paper's n_paper: the
    chance that both one-sided tests reject at alpha, treating them as independent (their
    statistics are negatively correlated, so this is a lower bound's neighbour, a guide)."""
    z = stats.norm.ppf(1 - alpha)
    lo = (1 - low) * m / (s * math.sqrt(1 / n_ours + low * low / n_paper))
    hi = (high - 1) * m / (s * math.sqrt(1 / n_ours + high * high / n_paper))
    return float(stats.norm.cdf(lo - z) * stats.norm.cdf(hi - z))


def fisher(k1, n1, k2, n2):
    """Fisher's exact test (two-sided) of k1 of n1 against k2 of n2: {"p", "odds_ratio"}
    (scipy.stats.fisher_exact on [[k1, n1 - k1], [k2, n2 - k2]])."""
    r = stats.fisher_exact([[k1, n1 - k1], [k2, n2 - k2]], alternative="two-sided")
    return {"p": float(r.pvalue), "odds_ratio": float(r.statistic)}


def verdict(welch_p, tost_p, alpha=ALPHA):
    """"equivalent" (the TOST rejects), else "different" (Welch rejects), else "undecided"."""
    if tost_p is not None and tost_p < alpha:
        return "equivalent"
    if welch_p is not None and welch_p < alpha:
        return "different"
    return "undecided"


def _paper(group):
    if group.get("room"):
        return None
    return paper.RESULTS.get((group.get("drive"), group["condition"]))


def figure_tests(summary):
    """One row per group and figure with the paper's mean, sd and n: ours and the paper's
    (mean, sd, n), the ratio, within 1.5x, Welch's and the TOST's p, the verdict."""
    rows = []
    for g in summary["groups"]:
        ref = _paper(g)
        if ref is None:
            continue
        for key, label in FIGURES:
            ours, theirs = g[key], ref[key]
            n = ours["reached"] if key == "first_trial_steps" else ours["seeds"]
            n_p = theirs.get("reached", paper.SEEDS)
            row = {"robot": g["robot"], "condition": g["condition"], "figure": label,
                   "paper": {"mean": theirs["mean"], "sd": theirs["sd"], "n": n_p},
                   "ours": {"mean": ours["mean"], "sd": ours["sd"], "n": n},
                   "ratio": None, "within_1_5x": None, "welch_p": None, "tost_p": None,
                   "power": None}
            if ours["mean"] is not None and ours["sd"] and n > 1:
                row["ratio"] = ours["mean"] / theirs["mean"]
                row["within_1_5x"] = LOW <= row["ratio"] <= HIGH
                row["welch_p"] = welch(ours["mean"], ours["sd"], n, theirs["mean"],
                                       theirs["sd"], n_p)["p"]
                row["tost_p"] = tost(ours["mean"], ours["sd"], n, theirs["mean"],
                                     theirs["sd"], n_p)["p"]
                row["power"] = power(theirs["mean"], theirs["sd"], n, n_p)
            row["verdict"] = verdict(row["welch_p"], row["tost_p"])
            rows.append(row)
    return rows


def shrink_rows(summary):
    """One row per group with a paper shrink: ours, its 95% bootstrap interval, the paper's
    point and whether the interval holds it."""
    rows = []
    for g in summary["groups"]:
        ref = _paper(g)
        if ref is None or g["shrink"] is None:
            continue
        ci = g.get("shrink_ci95")
        rows.append({"robot": g["robot"], "condition": g["condition"], "paper": ref["shrink"],
                     "ours": g["shrink"], "ci95": ci, "ratio": g["shrink"] / ref["shrink"],
                     "within_1_5x": LOW <= g["shrink"] / ref["shrink"] <= HIGH,
                     "paper_in_ci": None if ci is None else ci[0] <= ref["shrink"] <= ci[1]})
    return rows


def count_tests(summary):
    """C5 and C6 as exact tests of counts (two-wheel groups at the paper's budget): runs
    below 30 goals (paper 43 of 50) and below 49 goals (paper 0 of 50; 49 is the paper's
    worst run)."""
    from tasks.robots import DRIVES
    goals = paper.TWO_WHEEL_GOALS
    rows = []
    for g in summary["groups"]:
        if g.get("drive") != "two_wheel" or g.get("room") or \
                g["steps"] != DRIVES["two_wheel"].budget:
            continue
        if g["condition"] == "random":
            k, bar, k_p = g["goals"]["below_30"], 30, goals["random_below_30"]
            claim = "C5"
        else:
            k, bar, k_p = g["goals"].get("below_49"), goals["avoidance_min"], 0
            claim = "C6"
        if k is None:
            continue
        test = fisher(k, g["seeds"], k_p, paper.SEEDS)
        rows.append({"claim": claim, "robot": g["robot"], "condition": g["condition"],
                     "bar": bar, "ours": [k, g["seeds"]], "paper": [k_p, paper.SEEDS],
                     "p": test["p"], "verdict": "different" if test["p"] < ALPHA
                     else "not shown different"})
    return rows


def tested(summary):
    """summary.json's "tests" entry: the margin, alpha and the three kinds of rows."""
    return {"alpha": ALPHA, "margin": [LOW, HIGH],
            "figures": figure_tests(summary), "shrinks": shrink_rows(summary),
            "counts": count_tests(summary)}


def _f(v, digits=0):
    return "-" if v is None else f"{v:,.{digits}f}"


def _p(p):
    return "-" if p is None else ("<0.001" if p < 0.001 else f"{p:.3f}")


def figures_table(tests):
    lines = ["| robot | condition | figure | paper mean (sd, n) | ours mean (sd, n) | ours / paper "
             "| within 1.5x | Welch p | TOST p | verdict |",
             "|---|---|---|---:|---:|---:|:-:|---:|---:|---|"]
    for r in tests["figures"]:
        p, o = r["paper"], r["ours"]
        within = "-" if r["within_1_5x"] is None else ("yes" if r["within_1_5x"] else "no")
        lines.append(f"| {r['robot']} | {r['condition']} | {r['figure']} "
                     f"| {_f(p['mean'])} ({_f(p['sd'])}, {p['n']}) "
                     f"| {_f(o['mean'])} ({_f(o['sd'])}, {o['n']}) | {_f(r['ratio'], 2)} "
                     f"| {within} | {_p(r['welch_p'])} | {_p(r['tost_p'])} | {r['verdict']} |")
    return "\n".join(lines)


def shrinks_table(tests):
    lines = ["| robot | condition | paper | ours | ours 95% CI | paper in CI | ours / paper "
             "| within 1.5x |", "|---|---|---:|---:|---|:-:|---:|:-:|"]
    for r in tests["shrinks"]:
        ci = "-" if r["ci95"] is None else f"[{r['ci95'][0]:.2f}, {r['ci95'][1]:.2f}]"
        inside = "-" if r["paper_in_ci"] is None else ("yes" if r["paper_in_ci"] else "no")
        lines.append(f"| {r['robot']} | {r['condition']} | {r['paper']:.2f} | {r['ours']:.2f} "
                     f"| {ci} | {inside} | {r['ratio']:.2f} | {'yes' if r['within_1_5x'] else 'no'} |")
    return "\n".join(lines)


def counts_table(tests):
    lines = ["| claim | robot | condition | runs below | paper | ours | Fisher p | verdict |",
             "|---|---|---|---:|---:|---:|---:|---|"]
    for r in tests["counts"]:
        lines.append(f"| {r['claim']} | {r['robot']} | {r['condition']} | {r['bar']} goals "
                     f"| {r['paper'][0]}/{r['paper'][1]} | {r['ours'][0]}/{r['ours'][1]} "
                     f"| {_p(r['p'])} | {r['verdict']} |")
    return "\n".join(lines)


def tally(tests):
    """{"equivalent", "different", "undecided"} counts of the figures, and how many are
    within 1.5x."""
    out = {k: sum(r["verdict"] == k for r in tests["figures"])
           for k in ("equivalent", "different", "undecided")}
    out["within_1_5x"] = sum(bool(r["within_1_5x"]) for r in tests["figures"])
    out["figures"] = len(tests["figures"])
    return out


def section(tests, heading="##"):
    """REPORT.md's (and RESULTS.md's) lines: the three tables with a line saying how."""
    t = tally(tests)
    return [f"{heading} The figures tested against the paper", "",
            f"Welch's test (two-sided) and an equivalence test (two one-sided Welch tests, "
            f"margin {LOW:.3g}x-{HIGH:.3g}x the paper's mean) at alpha {ALPHA}, from the "
            f"paper's mean, sd and n and ours; a verdict: equivalent (the TOST rejects), "
            f"different (Welch rejects, the TOST does not), undecided. Of {t['figures']}: "
            f"{t['equivalent']} equivalent, {t['different']} different, {t['undecided']} "
            f"undecided; {t['within_1_5x']} within 1.5x (the point alone, not a test).", "",
            figures_table(tests), "",
            "The shrinks (steps per trial / first trial; the paper gives the point only):", "",
            shrinks_table(tests), "",
            "C5 and C6 as counts of runs (Fisher's exact test, two-sided):", "",
            counts_table(tests), ""]
