"""The figures' and claims' tests (experiments.outputs.verdicts; docs/interpretation.md,
"Testing the figures (protocol 8)"), each against a case computed by hand and scipy's own."""
import math

import pytest
from scipy import stats

from experiments import paper
from experiments.outputs import verdict_tables, verdicts


def test_welch_against_a_hand_computed_case():
    """Sample 1: mean 10, sd 2, n 5; sample 2: mean 7, sd 3, n 6. By hand: the standard
    error^2 is 4/5 + 9/6 = 2.3, t = 3 / sqrt(2.3) = 1.978141, the Welch-Satterthwaite df =
    2.3^2 / (0.8^2 / 4 + 1.5^2 / 5) = 5.29 / 0.61 = 8.672131."""
    got = verdicts.welch(10, 2, 5, 7, 3, 6)
    assert got["t"] == pytest.approx(1.978141, abs=1e-6)
    assert got["df"] == pytest.approx(5.29 / 0.61, rel=1e-12)
    assert got["p"] == pytest.approx(2 * stats.t.sf(3 / math.sqrt(2.3), 5.29 / 0.61), rel=1e-9)
    assert 0.05 < got["p"] < 0.1  # t = 1.98 on 8.7 df: between the 5% and 10% two-sided points
    # one-sided: half of it in the direction of the difference
    assert verdicts.welch(10, 2, 5, 7, 3, 6, "greater")["p"] == pytest.approx(got["p"] / 2)
    assert verdicts.welch(10, 2, 5, 7, 3, 6, "less")["p"] == pytest.approx(1 - got["p"] / 2)


def test_tost_against_a_hand_computed_case():
    """Ours: mean 80, sd 40, n 10; the paper: mean 100, sd 40, n 10; margin 2/3-3/2. The
    lower test is against the paper's sample times 2/3 (mean 66.67, sd 26.67): standard
    error^2 160 + 71.11 = 231.11, t = 13.333 / 15.202 = 0.87706; the upper against it times
    3/2 (150, 60): 160 + 360 = 520, t = -70 / 22.804 = -3.06970."""
    got = verdicts.tost(80, 40, 10, 100, 40, 10)
    se_lo = math.sqrt(1600 / 10 + (40 * 2 / 3) ** 2 / 10)
    se_hi = math.sqrt(1600 / 10 + 60 ** 2 / 10)
    assert se_lo == pytest.approx(15.2023, abs=1e-4) and se_hi == pytest.approx(22.8035, abs=1e-4)
    df_lo = verdicts.welch_df(40, 10, 40 * 2 / 3, 10)
    df_hi = verdicts.welch_df(40, 10, 60, 10)
    assert got["lower"] == pytest.approx(stats.t.sf(13.3333333 / se_lo, df_lo), rel=1e-6)
    assert got["upper"] == pytest.approx(stats.t.cdf(-70 / se_hi, df_hi), rel=1e-6)
    assert got["p"] == max(got["lower"], got["upper"]) == got["lower"]
    assert got["lower"] > 0.1 and got["upper"] < 0.005  # near the lower bound, far below the upper
    # equal samples well inside the margin: both one-sided tests reject
    assert verdicts.tost(100, 10, 50, 100, 10, 50)["p"] < 1e-10


def test_power_by_simulation_against_the_tests_own_arithmetic_and_the_normal_limit():
    """verdicts.power: the share of simulated pairs of gamma samples on which the TOST
    rejects. (1) Its draws recomputed here (the same generator, seed and shapes) and tested
    by scipy.stats.ttest_ind_from_stats give the same share; (2) mean 100, sd 50, 20 runs
    each: by hand the two one-sided statistics are normal with means +-d, d = 33.33 / (50
    sqrt(1/20 + (4/9)/20)) = 50 / (50 sqrt(1/20 + (9/4)/20)) = 2.4807, correlated r =
    (1/20 + 1/20) / sqrt((1/20 + (4/9)/20)(1/20 + (9/4)/20)) = 0.9231; the joint power
    P(T_lo > z, T_hi < -z) is the bivariate normal's cdf at (d - z, d - z) with correlation
    -r, 0.597, below the product of the two, 0.637: the simulation (t tails, a skewed gamma)
    is within 0.03 of it; (3) the extremes."""
    import numpy as np
    m, s, n1, n2 = 100.0, 50.0, 20, 20
    got = verdicts.power(m, s, n1, n2)
    rng = np.random.default_rng(verdicts.POWER_SEED)
    shape, scale = (m / s) ** 2, s * s / m
    a = rng.gamma(shape, scale, (verdicts.POWER_DRAWS, n1))
    b = rng.gamma(shape, scale, (verdicts.POWER_DRAWS, n2))
    ma, sa, mb, sb = a.mean(1), a.std(1, ddof=1), b.mean(1), b.std(1, ddof=1)
    lo = stats.ttest_ind_from_stats(ma, sa, n1, mb * 2 / 3, sb * 2 / 3, n2, equal_var=False,
                                    alternative="greater").pvalue
    hi = stats.ttest_ind_from_stats(ma, sa, n1, mb * 1.5, sb * 1.5, n2, equal_var=False,
                                    alternative="less").pvalue
    assert got == float(np.mean(np.maximum(lo, hi) < 0.05))
    d = (100 / 3) / (50 * math.sqrt(1 / 20 + (4 / 9) / 20))
    assert d == pytest.approx(50 / (50 * math.sqrt(1 / 20 + (9 / 4) / 20)))
    assert d == pytest.approx(2.4807, abs=1e-4)
    r = (2 / 20) / math.sqrt((1 / 20 + (4 / 9) / 20) * (1 / 20 + (9 / 4) / 20))
    assert r == pytest.approx(0.9231, abs=1e-4)
    z = stats.norm.ppf(0.95)
    joint = stats.multivariate_normal([0, 0], [[1, -r], [-r, 1]]).cdf([d - z, d - z])
    product = stats.norm.cdf(d - z) ** 2
    assert joint == pytest.approx(0.597, abs=2e-3) and product == pytest.approx(0.637, abs=2e-3)
    assert abs(got - joint) < 0.03
    assert verdicts.power(100, 1, 50, 50) == 1.0 and verdicts.power(100, 1e4, 50, 50) < 0.01
    # the same draws, a stricter alpha: fewer rejections
    assert verdicts.power(m, s, n1, n2, alpha=0.05 / 12) < got


def test_the_power_of_the_papers_figures_on_100_seeds():
    """docs/interpretation.md's table, "Testing the figures (protocol 8)": the first trials
    and the two-wheel random walk's steps per trial are weakly powered, the floating
    avoidance first trial about 0.88; the product of the two one-sided probabilities (the
    old guide) overstates the two-wheel random walk's first trial."""
    def at(drive, condition, key, n=100):
        ref = paper.RESULTS[(drive, condition)][key]
        return verdicts.power(ref["mean"], ref["sd"], n, ref.get("reached", paper.SEEDS))
    table = {("two_wheel", "random", "first_trial_steps"): 0.55,
             ("two_wheel", "random", "steps_per_trial"): 0.69,
             ("two_wheel", "avoidance", "first_trial_steps"): 0.48,
             ("floating", "random", "first_trial_steps"): 0.67,
             ("floating", "avoidance", "first_trial_steps"): 0.88}
    for key, want in table.items():
        assert at(*key) == pytest.approx(want, abs=0.005), key
    assert at("two_wheel", "avoidance", "steps_per_trial") > 0.999
    z = stats.norm.ppf(0.95)
    m, s = 6087, 5789
    product = (stats.norm.cdf((1 / 3) * m / (s * math.sqrt(1 / 100 + (2 / 3) ** 2 / 49)) - z)
               * stats.norm.cdf(0.5 * m / (s * math.sqrt(1 / 100 + 1.5 ** 2 / 49)) - z))
    assert product == pytest.approx(0.585, abs=1e-3) and at("two_wheel", "random",
                                                             "first_trial_steps") < product - 0.02


def test_rank_test_against_a_hand_computed_case():
    """C(n, k) / C(n + m, k): one of ours against one of the paper's, the smaller is ours
    with chance 1/2; two of ours against one, 2/3; 8 of 100 below the least of 50, by hand
    the product over i < 8 of (100 - i) / (150 - i) = 0.0354; scipy's hypergeometric pmf
    (all k drawn of k from n + m holding n of ours) the same; and by simulation, 10 of ours
    against 5 continuous draws with 2 or more below the least of the 5."""
    import numpy as np
    assert verdicts.rank_below(1, 1, 1) == pytest.approx(0.5)
    assert verdicts.rank_below(1, 2, 1) == pytest.approx(2 / 3)
    assert verdicts.rank_below(0, 100) == 1.0
    hand = math.prod((100 - i) / (150 - i) for i in range(8))
    assert hand == pytest.approx(0.0354, abs=1e-4)
    assert verdicts.rank_below(8, 100) == pytest.approx(hand, rel=1e-12)
    assert verdicts.rank_below(8, 100) == pytest.approx(stats.hypergeom(150, 100, 8).pmf(8),
                                                        rel=1e-9)
    x = np.random.default_rng(56).exponential(size=(40_000, 15))
    below = (x[:, :10] < x[:, 10:].min(axis=1, keepdims=True)).sum(axis=1)
    assert (below >= 2).mean() == pytest.approx(verdicts.rank_below(2, 10, 5), abs=0.01)


def test_binomial_most_against_a_hand_computed_case():
    """P(X >= k), X ~ Binomial(n, 1/2): 2 of 3, (3 + 1) / 8 = 0.5; 9 of 10, 11 / 1024;
    scipy.stats.binomtest's one-sided p the same."""
    assert verdicts.most_p(2, 3) == pytest.approx(0.5)
    assert verdicts.most_p(9, 10) == pytest.approx(11 / 1024)
    assert verdicts.most_p(0, 10) == 1.0
    for k, n in ((9, 10), (60, 100), (98, 100), (40, 100)):
        assert verdicts.most_p(k, n) == pytest.approx(
            stats.binomtest(k, n, 0.5, alternative="greater").pvalue, rel=1e-9)


def test_holm_against_a_hand_computed_case():
    """p = 0.01, 0.04, 0.03, 0.005 (m = 4): sorted, 0.005 x 4 = 0.02, 0.01 x 3 = 0.03,
    0.03 x 2 = 0.06, 0.04 x 1 = 0.04 -> running maximum 0.06; a None stays out of the
    family (m = 2 below)."""
    assert verdicts.holm([0.01, 0.04, 0.03, 0.005]) == pytest.approx([0.03, 0.06, 0.06, 0.02])
    got = verdicts.holm([0.02, None, 0.6])
    assert got[1] is None and got[0] == pytest.approx(0.04) and got[2] == pytest.approx(0.6)
    assert verdicts.holm([0.5, 0.4]) == pytest.approx([0.8, 0.8])
    assert verdicts.holm([0.7, 0.9, 0.8]) == pytest.approx([1.0, 1.0, 1.0])  # capped


def test_shrink_test_against_a_hand_computed_case():
    """Ours 0.5 (log se 0.1), the paper's 0.4 (0.2): d = ln 1.25 = 0.22314, se = sqrt(0.05)
    = 0.22361, z = 0.99793, two-sided p 0.3183; lower (d - ln 2/3) / se = 2.81122, p
    0.00247; upper (d - ln 3/2) / se = -0.81537, p 0.2074; the equivalence p the larger."""
    got = verdicts.shrink_test(0.5, 0.1, 0.4, 0.2)
    se = math.sqrt(0.05)
    assert got["z"] == pytest.approx(math.log(1.25) / se) == pytest.approx(0.99793, abs=1e-5)
    assert got["difference_p"] == pytest.approx(2 * stats.norm.sf(0.99793), abs=1e-5)
    assert got["difference_p"] == pytest.approx(0.3183, abs=1e-4)
    assert got["lower"] == pytest.approx(stats.norm.sf(2.81122), rel=1e-4)
    assert got["upper"] == pytest.approx(stats.norm.cdf(-0.81537), rel=1e-4)
    assert got["equivalence_p"] == got["upper"] == pytest.approx(0.2074, abs=1e-4)
    # the standard error an interval implies, and the paper's own by the delta method
    assert verdicts.log_se_of_interval([math.exp(-1.959964), math.exp(1.959964)]) == \
        pytest.approx(1.0, rel=1e-6)
    ref = paper.RESULTS[("two_wheel", "random")]
    hand = math.sqrt((3336 / 3844) ** 2 / 50 + (5789 / 6087) ** 2 / 49)
    assert verdicts.paper_shrink_se(ref) == pytest.approx(hand) == pytest.approx(0.183, abs=1e-3)
    hand = math.sqrt(hand ** 2 - 2 * 0.5 * (3336 / 3844) * (5789 / 6087) / 49)
    assert verdicts.paper_shrink_se(ref, 0.5) == pytest.approx(hand) == \
        pytest.approx(0.129, abs=1e-3)
    # power: paper se 0.1, 50 against 50: se = 0.1 sqrt(2), ln 1.5 / se = 2.86707; Phi(2.86707
    # - 1.64485) - Phi(1.64485 - 2.86707) = Phi(1.22222) - Phi(-1.22222) = 0.77837
    assert verdicts.shrink_power(0.1, 50, 50) == pytest.approx(
        stats.norm.cdf(1.22222) - stats.norm.cdf(-1.22222), abs=1e-5)
    assert verdicts.shrink_power(0.1, 50, 50) == pytest.approx(0.7784, abs=1e-4)


def test_fisher_against_a_hand_computed_case():
    """1 of 3 against 3 of 3: of the hypergeometric 4 successes in 6, 3 in the first row,
    P(1) = 4/20, P(2) = 12/20, P(3) = 4/20; the two-sided p sums those no likelier than
    the observed 0.2: 0.4."""
    assert verdicts.fisher(1, 3, 3, 3)["p"] == pytest.approx(0.4)
    # C6's shape: 0 of 50 against 0 of 100 is no difference at all
    assert verdicts.fisher(0, 100, 0, 50)["p"] == pytest.approx(1.0)
    # 10 of 100 against 0 of 50, by the definition: X, the first row's count of the 10,
    # is hypergeometric (150 runs, 10 marked, 100 drawn); p sums P(x) <= P(10).
    def prob(x):
        return math.comb(10, x) * math.comb(140, 100 - x) / math.comb(150, 100)
    hand = sum(prob(x) for x in range(11) if prob(x) <= prob(10) * (1 + 1e-9))
    assert 0.005 < hand < 0.05
    assert verdicts.fisher(10, 100, 0, 50)["p"] == pytest.approx(hand, rel=1e-9)


def test_verdict_rules():
    assert verdicts.verdict(0.001, 0.01) == "equivalent and different"  # both reject
    assert verdicts.verdict(0.3, 0.01) == "equivalent"
    assert verdicts.verdict(0.001, 0.2) == "different"
    assert verdicts.verdict(0.3, 0.2) == "undecided"
    assert verdicts.verdict(None, None) == "undecided"
    assert verdicts.verdict(0.05, 0.05) == "undecided"  # p < alpha rejects, p = alpha does not


def _group(drive, condition, first, per, goals, steps=30_000, seeds=100):
    shrink = per["mean"] / first["mean"]
    return {"robot": drive, "condition": condition, "drive": drive, "steps": steps,
            "seeds": seeds, "first_trial_steps": dict(first), "steps_per_trial": dict(per),
            "shrink": shrink, "shrink_ci95": [shrink * 0.8, shrink * 1.25], "goals": goals}


def _paper_as_ours():
    groups = []
    for (drive, condition), ref in paper.RESULTS.items():
        first = dict(ref["first_trial_steps"], reached=ref["first_trial_steps"].get("reached", 50))
        per = dict(ref["steps_per_trial"], seeds=50)
        goals = {"below_30": 40 if condition == "random" else 0, "below_49": 3, "min": 45}
        groups.append(_group(drive, condition, first, per, goals,
                             steps=30_000 if drive == "two_wheel" else 100_000, seeds=50))
    return {"groups": groups}


def test_a_summary_tested_figure_by_figure():
    """The paper's own figures as ours: every figure and shrink equivalent or undecided,
    never different, the ratio 1; the families' sizes (14, 12, 9) and Holm's p beside
    each raw one; C5 and C6's counts tested as given, C6 by the rank test."""
    tests = verdicts.tested(_paper_as_ours())
    assert len(tests["figures"]) == 8 and len(tests["shrinks"]) == 4 and len(tests["counts"]) == 2
    assert {k: v["tests"] for k, v in tests["families"].items()} == \
        {"difference": 14, "equivalence": 12, "claims": 9}
    for row in tests["figures"]:
        assert row["ratio"] == pytest.approx(1.0) and row["within_1_5x"]
        assert row["difference_p"] == pytest.approx(1.0)
        assert row["verdict"] in ("equivalent", "undecided")
        assert row["difference_p_holm"] >= row["difference_p"] * 0.999
        assert row["equivalence_p_holm"] >= row["equivalence_p"]
        assert 0 <= row["power_holm_step"] <= row["power"] <= 1
    small_sd = [r for r in tests["figures"] if r["figure"] == "steps per trial"
                and r["condition"] == "avoidance"]
    assert all(r["verdict"] == "equivalent" for r in small_sd)  # sds of a third of the mean
    for row in tests["shrinks"]:  # the paper's stated shrink is not quite its means' ratio
        assert row["verdict"] in ("equivalent", "undecided") and row["difference_p"] > 0.8
        assert row["sensitivity"]["rho"] == 0.5
        assert row["sensitivity"]["paper_se"] < row["paper_se"]
    c5, c6 = tests["counts"]
    assert (c5["claim"], c5["ours"], c5["paper"]) == ("C5", [40, 50], [43, 50])
    assert c5["p"] == c5["fisher_p"] == pytest.approx(verdicts.fisher(40, 50, 43, 50)["p"])
    assert (c6["claim"], c6["ours"], c6["paper"]) == ("C6", [3, 50], [0, 50])
    # 3 of 50 below the least of 50: C(50, 3) / C(100, 3) = 19,600 / 161,700
    assert c6["p"] == pytest.approx(19_600 / 161_700) and c6["test"].startswith("rank")
    assert c6["fisher_p"] == pytest.approx(verdicts.fisher(3, 50, 0, 50)["p"])
    assert c6["verdict"] == "not shown different"
    claims = tests["claims"]
    assert len(claims) == 10 and all(c["holds"] for c in claims)
    text = "\n".join(verdict_tables.section(tests))
    assert "| two_wheel | random | first-trial steps | 6,087 (5,789, 49) |" in text
    assert "family-wise, by Holm's p" in text


def test_a_figure_far_from_the_paper_is_different():
    first = {"mean": 2900, "sd": 2400, "reached": 100}
    per = {"mean": 1000, "sd": 500, "seeds": 100}
    tests = verdicts.tested({"groups": [_group("two_wheel", "random", first, per,
                                               {"below_30": 10, "below_49": 40})]})
    rows = {r["figure"]: r for r in tests["figures"]}
    assert rows["first-trial steps"]["verdict"] == "different"
    assert not rows["first-trial steps"]["within_1_5x"]  # 0.48x
    assert tests["counts"][0]["verdict"] == "different"  # 10 of 100 against 43 of 50


def test_within_the_margin_and_different_is_said_both_ways():
    """Protocol 7's two-wheel avoidance steps per trial (359 +- 142 of 100 against 283 +-
    98 of 50, 1.27x): the TOST and Welch both reject, so "equivalent and different"."""
    per = {"mean": 359.406, "sd": 142.014, "seeds": 100}
    first = {"mean": 1046.19, "sd": 902.24, "reached": 100}
    tests = verdicts.tested({"groups": [_group("two_wheel", "avoidance", first, per,
                                               {"below_30": 0, "below_49": 8, "min": 33})]})
    row = next(r for r in tests["figures"] if r["figure"] == "steps per trial")
    assert row["difference_p"] == pytest.approx(stats.ttest_ind_from_stats(
        359.406, 142.014, 100, 283, 98, 50, equal_var=False).pvalue)
    assert row["difference_p"] < 0.001 and row["equivalence_p"] < 0.01
    assert row["verdict"] == "equivalent and different"
    c6 = tests["counts"][0]  # 8 of 100 below 49: the rank test 0.035 decides, Fisher 0.052
    assert c6["p"] == pytest.approx(0.0354, abs=1e-4) and c6["verdict"] == "different"
    assert c6["fisher_p"] == pytest.approx(0.0524, abs=1e-4)


def test_a_claim_is_judged_by_its_test_not_its_point():
    """The hovercraft's first trials (5,198 against 4,765, 1.1x) with sds of 4,000 on 32
    runs each: the point says "cuts", the one-sided Welch test (scipy's) does not reject,
    so the claim does not hold; with sds of 400 it does."""
    def claims(sd):
        groups = [_group("floating", c, {"mean": m, "sd": sd, "reached": 32},
                         {"mean": m / 2, "sd": sd / 2, "seeds": 32}, {"below_30": 0},
                         steps=100_000, seeds=32)
                  for c, m in (("random", 5198.0), ("avoidance", 4765.0))]
        return {c["claim"]: c for c in verdicts.claim_tests({"groups": groups})}
    row = claims(4000.0)["floating: avoidance cuts first-trial steps (paper 2.0x)"]
    want = stats.ttest_ind_from_stats(5198, 4000, 32, 4765, 4000, 32, equal_var=False,
                                      alternative="greater").pvalue
    assert row["ours"] == "1.1x" and row["p"] == pytest.approx(want) and want > 0.3
    assert not row["holds"]
    assert claims(400.0)["floating: avoidance cuts first-trial steps (paper 2.0x)"]["holds"]
    # a shrink of 0.9 whose interval is [0.72, 1.125]: log se ln(1.5625) / 3.92 = 0.1139,
    # z = ln 0.9 / 0.1139 = -0.925, one-sided p 0.178: not shown
    shrink = claims(4000.0)["floating random: learning shrinks trials (paper 76%)"]
    assert shrink["p"] == pytest.approx(stats.norm.cdf(math.log(0.5) / (
        math.log(1.5625) / (2 * stats.norm.ppf(0.975)))))


def test_welch_is_scipys_ttest_from_stats_bit_for_bit():
    """verdicts.welch does scipy.stats.ttest_ind_from_stats' arithmetic itself (its
    import was most of a report's start): the same t and p, to the last bit, on the
    shapes of our summaries (means and sds of steps, 2-120 runs) and every alternative."""
    import numpy as np
    rng = np.random.default_rng(48)
    for _ in range(3000):
        m1, m2 = rng.uniform(50, 20_000, 2)
        s1, s2 = rng.uniform(5, 15_000, 2)
        n1, n2 = (int(n) for n in rng.integers(2, 121, 2))
        for alternative in ("two-sided", "greater", "less"):
            ours = verdicts.welch(m1, s1, n1, m2, s2, n2, alternative)
            theirs = stats.ttest_ind_from_stats(m1, s1, n1, m2, s2, n2, equal_var=False,
                                                alternative=alternative)
            assert (ours["t"], ours["p"]) == (float(theirs.statistic), float(theirs.pvalue))

