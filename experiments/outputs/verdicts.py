"""Section 3.6's figures and claims tested (docs/interpretation.md, "Testing the figures
(protocol 8)", written before protocol 8's run; issues 48 and 56): the one judge of every
report, headline, fit and multiverse.

Against the paper (each of our figures against the paper's mean, sd and n):

- the eight figures (first trial, steps per trial; both robots, both conditions): Welch's
  test, two-sided (`welch`, difference), and two one-sided Welch tests against the margin
  LOW-HIGH times the paper's mean (`tost`, equivalence);
- the four shrinks (steps per trial / first trial): the same two questions on the log scale
  by normal z tests with both samples' error (`shrink_test`): ours from our bootstrap
  interval, the paper's by the delta method from its own sds and n, with RHO (the paper's
  unreported correlation of a run's two figures) deciding and RHO_SENSITIVITY beside;
- C5's count (runs below 30 goals) by Fisher's exact test (`fisher`); C6's (runs below the
  paper's worst, 49 goals) by the rank test (`rank_below`), Fisher's beside it.

Each figure and shrink gets one of four verdicts (`verdict`) from the raw p values at ALPHA;
each p value is also given Holm-adjusted (`holm`) within its family (FAMILIES); each figure's
equivalence test has its power by simulation (`power`, a gamma with the paper's mean and sd).

The qualitative claims are judged on our runs by a test in the claim's direction
(`claim_tests`): avoidance cuts steps (one-sided Welch between the conditions), learning
shrinks trials (one-sided z of the log shrink), most random walks below 30 goals (one-sided
binomial), every avoidance run at 49 goals or more (not contradicted by the rank test).

The markdown tables are experiments.outputs.verdict_tables'.
"""
import functools
import math

import numpy as np
from scipy import special

from experiments import paper
from tasks.robots import DRIVES

ALPHA = 0.05
#: The equivalence margin, as ratios of our mean (or shrink) to the paper's
#: (docs/interpretation.md, "Testing the figures", chosen before protocol 7's runs).
LOW, HIGH = 2.0 / 3.0, 1.5
#: The figures with a paper mean, sd and n (experiments.paper.RESULTS' keys).
FIGURES = (("first_trial_steps", "first-trial steps"), ("steps_per_trial", "steps per trial"))
#: The paper's unreported correlation between a run's first trial and its steps per trial:
#: the value that decides the shrink tests, and the one reported beside it.
RHO, RHO_SENSITIVITY = 0.0, 0.5
#: The power simulation: draws of both samples, and its seed (deterministic reports).
POWER_DRAWS, POWER_SEED = 4000, 200_008
#: The normal distribution's 97.5% point: a 95% interval's half width in standard errors.
Z975 = float(special.ndtri(0.975))
#: The four verdicts of a figure or a shrink against the paper (`verdict`).
VERDICTS = ("equivalent", "different", "equivalent and different", "undecided")
#: The three families of tests whose p values are Holm-adjusted together.
FAMILIES = {"difference": "different from the paper: the figures, the shrinks, C5 and C6",
            "equivalence": "equivalent to the paper: the figures and the shrinks",
            "claims": "the claims shown on our runs (C6, not contradicted, is judged by the "
                      "rank test of the difference family)"}


def _welch_arrays(m1, s1, n1, m2, s2, n2, alternative):
    """Welch's (t, df, p) on numbers or arrays of summaries (`welch`)."""
    vn1, vn2 = s1 ** 2 / n1, s2 ** 2 / n2
    with np.errstate(divide="ignore", invalid="ignore"):  # two samples without spread
        df = (vn1 + vn2) ** 2 / (vn1 ** 2 / (n1 - 1) + vn2 ** 2 / (n2 - 1))
        t = np.divide(m1 - m2, np.sqrt(vn1 + vn2))
    if alternative == "two-sided":
        p = 2 * special.stdtr(df, -np.abs(t))
    elif alternative == "greater":
        p = special.stdtr(df, -t)
    elif alternative == "less":
        p = special.stdtr(df, t)
    else:
        raise ValueError(f"alternative must be two-sided, greater or less, not {alternative!r}")
    return t, df, p


def welch_df(s1, n1, s2, n2):
    """Welch-Satterthwaite degrees of freedom of two samples' sds and sizes."""
    a, b = s1 * s1 / n1, s2 * s2 / n2
    return (a + b) ** 2 / (a * a / (n1 - 1) + b * b / (n2 - 1))


def welch(m1, s1, n1, m2, s2, n2, alternative="two-sided"):
    """Welch's t test of sample 1 against sample 2 from their means, sds (ddof 1) and
    sizes: {"t", "df", "p"}.

    scipy.stats.ttest_ind_from_stats(..., equal_var=False) step for step (its variances
    per size, its Welch-Satterthwaite df, the t distribution's tail by special.stdtr, on
    0-d arrays as it computes them: the same bits, tests/test_verdicts.py), written here
    because importing scipy.stats is the largest part of a report's start, paid by each
    `ebrl` command that builds a report (docs/speed.md, "The test suite's time")."""
    m1, s1, m2, s2 = (np.asarray(v, dtype=np.float64) for v in (m1, s1, m2, s2))
    t, _, p = _welch_arrays(m1, s1, n1, m2, s2, n2, alternative)
    return {"t": float(t), "df": float(welch_df(float(s1), n1, float(s2), n2)), "p": float(p)}


def tost(m1, s1, n1, m2, s2, n2, low=LOW, high=HIGH):
    """Equivalence of sample 1's mean to between low and high times sample 2's: two
    one-sided Welch tests, H0 mu1 <= low mu2 (against sample 2 scaled by low: a sample of
    k X has mean k m and sd k s, so this keeps the paper's own sampling error) and H0 mu1
    >= high mu2 (scaled by high). {"lower", "upper" (each test's p), "p" (the larger)}."""
    lower = welch(m1, s1, n1, low * m2, low * s2, n2, alternative="greater")["p"]
    upper = welch(m1, s1, n1, high * m2, high * s2, n2, alternative="less")["p"]
    return {"lower": lower, "upper": upper, "p": max(lower, upper)}


@functools.lru_cache(maxsize=64)
def _simulated_tost_p(m, s, n_ours, n_paper, draws=POWER_DRAWS, seed=POWER_SEED):
    """The equivalence test's p on `draws` pairs of samples, n_ours and n_paper values,
    both from the gamma with mean m and sd s (shape (m / s)^2, scale s^2 / m)."""
    rng = np.random.default_rng(seed)
    shape, scale = (m / s) ** 2, s * s / m
    ours, theirs = rng.gamma(shape, scale, (draws, n_ours)), rng.gamma(shape, scale,
                                                                         (draws, n_paper))
    m1, s1 = ours.mean(axis=1), ours.std(axis=1, ddof=1)
    m2, s2 = theirs.mean(axis=1), theirs.std(axis=1, ddof=1)
    lower = _welch_arrays(m1, s1, n_ours, LOW * m2, LOW * s2, n_paper, "greater")[2]
    upper = _welch_arrays(m1, s1, n_ours, HIGH * m2, HIGH * s2, n_paper, "less")[2]
    return np.maximum(lower, upper)


def power(m, s, n_ours, n_paper, alpha=ALPHA):
    """The equivalence test's power when our runs are drawn exactly as the paper's: the
    share of POWER_DRAWS simulated pairs of samples (a gamma with the paper's mean m and sd
    s; n_ours of ours, n_paper of the paper's; seed POWER_SEED) on which `tost` rejects at
    alpha. Simulated, not a product of the two one-sided tests' probabilities: their
    statistics are positively correlated (both rise with our mean), so the product
    overstates the joint power."""
    return float(np.mean(_simulated_tost_p(float(m), float(s), int(n_ours), int(n_paper))
                         < alpha))


def normal_p(z, alternative="two-sided"):
    """The standard normal's p of z (scipy.special.ndtr, the normal cdf): two-sided,
    "greater" (H1 above 0) or "less"."""
    if alternative == "two-sided":
        return float(2 * special.ndtr(-abs(z)))
    return float(special.ndtr(-z if alternative == "greater" else z))


def log_se_of_interval(ci):
    """The standard error on the log scale that a 95% interval [lo, hi] of a positive
    ratio implies: (ln hi - ln lo) / (2 Z975); None without an interval (or with one that
    is not an interval of a positive ratio)."""
    if not ci or ci[0] <= 0 or ci[1] < ci[0]:
        return None
    return (math.log(ci[1]) - math.log(ci[0])) / (2 * Z975)


def paper_shrink_se(ref, rho=RHO):
    """The paper's shrink's standard error on the log scale, by the delta method from its
    figures (ref: experiments.paper.RESULTS' entry): the shrink is the mean steps per trial
    over the mean first trial of the same runs, so var = cv_per^2 / n_per + cv_first^2 /
    n_first - 2 rho cv_per cv_first / min(n_per, n_first), cv = sd / mean, rho the
    correlation of a run's two figures (unreported: RHO decides)."""
    f, p = ref["first_trial_steps"], ref["steps_per_trial"]
    n_f, n_p = f.get("reached", paper.SEEDS), p.get("reached", paper.SEEDS)
    cv_f, cv_p = f["sd"] / f["mean"], p["sd"] / p["mean"]
    return math.sqrt(cv_p ** 2 / n_p + cv_f ** 2 / n_f - 2 * rho * cv_p * cv_f / min(n_f, n_p))


def shrink_test(ours, ours_se, theirs, theirs_se, low=LOW, high=HIGH):
    """Our shrink against the paper's on the log scale, each with its standard error:
    {"z", "difference_p" (two-sided), "lower", "upper" (the one-sided z tests against ln
    low and ln high), "equivalence_p" (the larger)}."""
    d, se = math.log(ours) - math.log(theirs), math.hypot(ours_se, theirs_se)
    lower = normal_p((d - math.log(low)) / se, "greater")
    upper = normal_p((d - math.log(high)) / se, "less")
    return {"z": d / se, "difference_p": normal_p(d / se), "lower": lower, "upper": upper,
            "equivalence_p": max(lower, upper)}


def shrink_power(theirs_se, n_paper, n_ours, alpha=ALPHA):
    """The shrink equivalence test's power when our runs are drawn as the paper's (our
    standard error the paper's times sqrt(n_paper / n_ours)): one normal statistic, so
    Phi(ln HIGH / se - z) - Phi(ln LOW / se + z), z the normal's 1 - alpha point (the
    margin is symmetric on the log scale)."""
    se = theirs_se * math.sqrt(1 + n_paper / n_ours)
    z = float(special.ndtri(1 - alpha))
    return max(0.0, float(special.ndtr(math.log(HIGH) / se - z)
                          - special.ndtr(math.log(LOW) / se + z)))


def fisher(k1, n1, k2, n2):
    """Fisher's exact test (two-sided) of k1 of n1 against k2 of n2: {"p", "odds_ratio"}
    (scipy.stats.fisher_exact on [[k1, n1 - k1], [k2, n2 - k2]]; imported here, as only
    reports of two-wheel runs at the paper's budget test counts)."""
    from scipy import stats
    r = stats.fisher_exact([[k1, n1 - k1], [k2, n2 - k2]], alternative="two-sided")
    return {"p": float(r.pvalue), "odds_ratio": float(r.statistic)}


def rank_below(k, n, m=paper.SEEDS):
    """The rank test: if our n runs and the paper's m come from one continuous distribution,
    the chance that k or more of ours fall below the least of the paper's, C(n, k) / C(n +
    m, k) (the k smallest of the n + m pooled all ours; scipy.stats.hypergeom's pmf at k of
    k drawn, tests/test_verdicts.py). With ties (whole goals) and ours counted strictly
    below, conservative."""
    return math.comb(n, k) / math.comb(n + m, k)


def most_p(k, n):
    """One-sided exact binomial test that more than half of n runs are marked, k of them:
    P(X >= k), X ~ Binomial(n, 1/2) (scipy.special.bdtrc)."""
    return 1.0 if k <= 0 else float(special.bdtrc(k - 1, n, 0.5))


def holm(ps):
    """Holm's step-down adjustment of a family's p values (None: not in the family, left
    None): the i-th smallest of m times m - i + 1, the running maximum, capped at 1."""
    given = [(p, i) for i, p in enumerate(ps) if p is not None]
    out, running = [None] * len(ps), 0.0
    for rank, (p, i) in enumerate(sorted(given)):
        running = max(running, min(1.0, (len(given) - rank) * p))
        out[i] = running
    return out


def verdict(difference_p, equivalence_p, alpha=ALPHA):
    """One of VERDICTS: "equivalent and different" (both tests reject), "equivalent" (the
    equivalence test alone), "different" (the difference test alone), else "undecided"."""
    eq = equivalence_p is not None and equivalence_p < alpha
    diff = difference_p is not None and difference_p < alpha
    return VERDICTS[3 if not (eq or diff) else 2 if eq and diff else 0 if eq else 1]


def _paper(group):
    if group.get("room"):
        return None
    return paper.RESULTS.get((group.get("drive"), group["condition"]))


def figure_tests(summary):
    """One row per group and figure with the paper's mean, sd and n: ours and the paper's
    (mean, sd, n), the ratio, within 1.5x, the difference and equivalence tests' p, the
    equivalence test's power, the verdict."""
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
                   "ratio": None, "within_1_5x": None, "difference_p": None,
                   "equivalence_p": None, "power": None}
            if ours["mean"] is not None and ours["sd"] and n > 1:
                row["ratio"] = ours["mean"] / theirs["mean"]
                row["within_1_5x"] = LOW <= row["ratio"] <= HIGH
                row["difference_p"] = welch(ours["mean"], ours["sd"], n, theirs["mean"],
                                            theirs["sd"], n_p)["p"]
                row["equivalence_p"] = tost(ours["mean"], ours["sd"], n, theirs["mean"],
                                            theirs["sd"], n_p)["p"]
                row["power"] = power(theirs["mean"], theirs["sd"], n, n_p)
            row["verdict"] = verdict(row["difference_p"], row["equivalence_p"])
            rows.append(row)
    return rows


def shrink_rows(summary):
    """One row per group with a paper shrink: ours with its log-scale standard error (from
    its bootstrap interval), the paper's with its own (RHO), the two tests, their verdict,
    the equivalence test's power and the same at RHO_SENSITIVITY."""
    rows = []
    for g in summary["groups"]:
        ref = _paper(g)
        if ref is None or g["shrink"] is None:
            continue
        ci, theirs = g.get("shrink_ci95"), ref["shrink"]
        ours_se = log_se_of_interval(ci)
        n_ours = g["first_trial_steps"]["reached"]
        n_paper = ref["first_trial_steps"].get("reached", paper.SEEDS)
        row = {"robot": g["robot"], "condition": g["condition"], "paper": theirs,
               "ours": g["shrink"], "ci95": ci, "ratio": g["shrink"] / theirs,
               "within_1_5x": LOW <= g["shrink"] / theirs <= HIGH, "ours_se": ours_se,
               "rho": RHO, "paper_se": paper_shrink_se(ref, RHO), "difference_p": None,
               "equivalence_p": None, "power": None,
               "sensitivity": {"rho": RHO_SENSITIVITY,
                               "paper_se": paper_shrink_se(ref, RHO_SENSITIVITY),
                               "difference_p": None, "equivalence_p": None}}
        if ours_se is not None and g["shrink"] > 0:
            for where in (row, row["sensitivity"]):
                test = shrink_test(g["shrink"], ours_se, theirs, where["paper_se"])
                where["difference_p"] = test["difference_p"]
                where["equivalence_p"] = test["equivalence_p"]
            row["power"] = shrink_power(row["paper_se"], n_paper, n_ours)
        for where in (row, row["sensitivity"]):
            where["verdict"] = verdict(where["difference_p"], where["equivalence_p"])
        rows.append(row)
    return rows


def _at_two_wheel_budget(group):
    return group.get("drive") == "two_wheel" and not group.get("room") and \
        group["steps"] == DRIVES["two_wheel"].budget


def count_tests(summary):
    """C5 and C6 as exact tests of counts (two-wheel groups at the paper's budget): runs
    below 30 goals against the paper's 43 of 50 (Fisher's test decides), and below 49 (the
    paper's worst run: its 0 of 50 is 0 by construction; the rank test decides, Fisher's
    beside it). "p" is the deciding test's."""
    goals = paper.TWO_WHEEL_GOALS
    rows = []
    for g in summary["groups"]:
        if not _at_two_wheel_budget(g):
            continue
        if g["condition"] == "random":
            k, bar, k_p = g["goals"]["below_30"], 30, goals["random_below_30"]
            claim, test = "C5", "Fisher (two-sided)"
        else:
            k, bar, k_p = g["goals"].get("below_49"), goals["avoidance_min"], 0
            claim, test = "C6", "rank (one-sided)"
        if k is None:
            continue
        fisher_p = fisher(k, g["seeds"], k_p, paper.SEEDS)["p"]
        p = fisher_p if claim == "C5" else rank_below(k, g["seeds"])
        rows.append({"claim": claim, "robot": g["robot"], "condition": g["condition"],
                     "bar": bar, "ours": [k, g["seeds"]], "paper": [k_p, paper.SEEDS],
                     "test": test, "p": p, "fisher_p": fisher_p,
                     "verdict": "different" if p < ALPHA else "not shown different"})
    return rows


def cut_p(random, avoidance, key):
    """One-sided Welch test that the random walk's mean of figure key is above the
    avoidance condition's, from two summary groups (first trials: the runs that reached
    the goal); None where either cannot be tested."""
    r, a = random[key], avoidance[key]
    n_r, n_a = (r.get("reached", r.get("seeds")), a.get("reached", a.get("seeds")))
    if None in (r["mean"], a["mean"], r.get("sd"), a.get("sd")) or min(n_r, n_a) < 2 \
            or not (r["sd"] or a["sd"]):
        return None
    return welch(r["mean"], r["sd"], n_r, a["mean"], a["sd"], n_a, alternative="greater")["p"]


def shrinks_p(group):
    """One-sided z test that a group's shrink is below 1 on the log scale, its standard
    error from its bootstrap interval; None without a shrink or an interval."""
    se = log_se_of_interval(group.get("shrink_ci95"))
    if group["shrink"] is None or group["shrink"] <= 0 or not se:
        return None
    return normal_p(math.log(group["shrink"]) / se, "less")


def claim_tests(summary):
    """Section 3.6's qualitative claims for each robot with the paper's figures, each judged
    by a test on our runs: rows of {"claim", "ours", "test", "p", "p_holm", "holds"}; a
    claim holds when its p < ALPHA (C6: when the rank test does not show it wrong), Holm's
    p beside (the claims family, C6 left out of it)."""
    by = {(g["robot"], g["condition"]): g for g in summary["groups"]}
    rows = []
    for robot in dict.fromkeys(g["robot"] for g in summary["groups"]):
        r, a = by.get((robot, "random")), by.get((robot, "avoidance"))
        if not (r and a) or _paper(r) is None:
            continue
        ref = {c: paper.RESULTS[(r["drive"], c)] for c in paper.CONDITIONS}
        for key, what in (("first_trial_steps", "avoidance cuts first-trial steps"),
                          ("steps_per_trial", "avoidance cuts steps per trial")):
            if r[key]["mean"] and a[key]["mean"]:
                factor = ref["random"][key]["mean"] / ref["avoidance"][key]["mean"]
                label = f"{robot}: {what}" + (f" (paper {factor:.1f}x)" if key ==
                                             "first_trial_steps" else "")
                rows.append(_claim(label, f"{r[key]['mean'] / a[key]['mean']:.1f}x",
                                   "Welch, one-sided", cut_p(r, a, key)))
        for g in (r, a):
            if g["shrink"] is not None:
                ci = g["shrink_ci95"]
                rows.append(_claim(
                    f"{robot} {g['condition']}: learning shrinks trials (paper "
                    f"{ref[g['condition']]['shrink']:.0%})",
                    f"{g['shrink']:.0%}" + (f" (95% CI {ci[0]:.0%}-{ci[1]:.0%})" if ci else ""),
                    "z on the log shrink, one-sided", shrinks_p(g)))
        if _at_two_wheel_budget(r) and _at_two_wheel_budget(a):
            goals = paper.TWO_WHEEL_GOALS
            k, n = r["goals"]["below_30"], r["seeds"]
            rows.append(_claim(f"{robot} random: most runs reach fewer than 30 goals in 30,000 "
                               f"steps (paper {goals['random_below_30']}/50)", f"{k}/{n}",
                               "binomial against a half, one-sided", most_p(k, n)))
            k = a["goals"].get("below_49")
            p = None if k is None else rank_below(k, a["seeds"])
            rows.append({"claim": f"{robot} avoidance: every run reaches at least "
                                  f"{goals['avoidance_min']} goals (paper min "
                                  f"{goals['avoidance_min']})",
                         "ours": f"min {a['goals']['min']}, {k}/{a['seeds']} below",
                         "test": "rank, not contradicted", "p": p, "p_holm": None,
                         "holds": p is not None and p >= ALPHA})
    family = [row for row in rows if row["test"] != "rank, not contradicted"]
    for row, adjusted in zip(family, holm([row["p"] for row in family])):
        row["p_holm"] = adjusted
    return rows


def _claim(label, ours, test, p):
    return {"claim": label, "ours": ours, "test": test, "p": p, "p_holm": None,
            "holds": p is not None and p < ALPHA}


def tested(summary):
    """summary.json's "tests" entry: alpha, the margin, RHO, the families' sizes and the
    rows (figures, shrinks, counts, claims), each p beside its Holm-adjusted value."""
    figures, shrinks = figure_tests(summary), shrink_rows(summary)
    counts, claims = count_tests(summary), claim_tests(summary)
    difference = [(r, "difference_p") for r in figures + shrinks] + [(r, "p") for r in counts]
    equivalence = [(r, "equivalence_p") for r in figures + shrinks]
    for family in (difference, equivalence):
        for (row, field), adjusted in zip(family, holm([row[f] for row, f in family])):
            row[f"{field}_holm"] = adjusted
    sizes = {"difference": sum(row[f] is not None for row, f in difference),
             "equivalence": sum(row[f] is not None for row, f in equivalence),
             "claims": sum(row["p_holm"] is not None for row in claims)}
    for row in figures:  # the power at Holm's strictest step, alpha / the family's size
        row["power_holm_step"] = None if row["power"] is None else power(
            row["paper"]["mean"], row["paper"]["sd"], row["ours"]["n"], row["paper"]["n"],
            ALPHA / max(sizes["equivalence"], 1))
    return {"alpha": ALPHA, "margin": [LOW, HIGH], "rho": RHO,
            "rho_sensitivity": RHO_SENSITIVITY, "power": {"distribution": "gamma",
                                                          "draws": POWER_DRAWS,
                                                          "seed": POWER_SEED},
            "families": {k: {"what": FAMILIES[k], "tests": sizes[k]} for k in FAMILIES},
            "figures": figures, "shrinks": shrinks, "counts": counts, "claims": claims}


def tally(tests):
    """Counts of the figures' and shrinks' verdicts (VERDICTS), by raw p and by Holm's
    (the "holm" entry), how many are within 1.5x and how many claims hold (raw, Holm)."""
    rows = tests["figures"] + tests["shrinks"]
    out = {k: sum(r["verdict"] == k for r in rows) for k in VERDICTS}
    holm_verdicts = [verdict(r.get("difference_p_holm"), r.get("equivalence_p_holm"))
                     for r in rows]
    out["holm"] = {k: holm_verdicts.count(k) for k in VERDICTS}
    out["within_1_5x"] = sum(bool(r["within_1_5x"]) for r in rows)
    out["tested"] = len(rows)
    claims = tests["claims"]
    out["claims"] = len(claims)
    out["claims_held"] = sum(bool(c["holds"]) for c in claims)
    out["claims_held_holm"] = sum(
        bool(c["holds"]) if c["p_holm"] is None else c["p_holm"] < ALPHA for c in claims)
    return out
