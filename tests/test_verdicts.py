"""The figures' tests against the paper (experiments.outputs.verdicts), each against a case
computed by hand."""
import math

import pytest
from scipy import stats

from experiments import paper
from experiments.outputs import verdicts


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


def test_power_against_a_hand_computed_case():
    """Mean 100, sd 100, 50 runs each, margin 2/3-3/2: both standardised distances are
    33.33 / (100 sqrt(0.02 + 0.02 * 4/9)) = 50 / (100 sqrt(0.02 + 0.02 * 9/4)) = 1.96116;
    the power is Phi(1.96116 - 1.64485)^2 = 0.62412^2 = 0.38953."""
    assert verdicts.power(100, 100, 50, 50) == pytest.approx(0.38953, abs=2e-5)
    assert verdicts.power(100, 1, 50, 50) == pytest.approx(1.0)
    assert verdicts.power(100, 1e6, 50, 50) < 0.01


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
    assert verdicts.verdict(0.001, 0.01) == "equivalent"  # within the margin, though different
    assert verdicts.verdict(0.001, 0.2) == "different"
    assert verdicts.verdict(0.3, 0.2) == "undecided"
    assert verdicts.verdict(None, None) == "undecided"


def _group(drive, condition, first, per, goals, steps=30_000, seeds=100):
    return {"robot": drive, "condition": condition, "drive": drive, "steps": steps,
            "seeds": seeds, "first_trial_steps": dict(first), "steps_per_trial": dict(per),
            "shrink": per["mean"] / first["mean"], "shrink_ci95": [0.2, 0.5], "goals": goals}


def test_a_summary_tested_figure_by_figure():
    """The paper's own figures as ours: every figure equivalent or undecided, never
    different, the ratio 1; C5 and C6's counts tested as given."""
    groups = []
    for (drive, condition), ref in paper.RESULTS.items():
        first = dict(ref["first_trial_steps"], reached=ref["first_trial_steps"].get("reached", 50))
        per = dict(ref["steps_per_trial"], seeds=50)
        goals = {"below_30": 40 if condition == "random" else 0, "below_49": 3}
        groups.append(_group(drive, condition, first, per, goals,
                             steps=30_000 if drive == "two_wheel" else 100_000, seeds=50))
    tests = verdicts.tested({"groups": groups})
    assert len(tests["figures"]) == 8 and len(tests["shrinks"]) == 4 and len(tests["counts"]) == 2
    for row in tests["figures"]:
        assert row["ratio"] == pytest.approx(1.0) and row["within_1_5x"]
        assert row["welch_p"] == pytest.approx(1.0) and row["verdict"] != "different"
    small_sd = [r for r in tests["figures"] if r["figure"] == "steps per trial"
                and r["condition"] == "avoidance"]
    assert all(r["verdict"] == "equivalent" for r in small_sd)  # sds of a third of the mean
    c5, c6 = tests["counts"]
    assert (c5["claim"], c5["ours"], c5["paper"]) == ("C5", [40, 50], [43, 50])
    assert c5["p"] == pytest.approx(verdicts.fisher(40, 50, 43, 50)["p"])
    assert (c6["claim"], c6["ours"], c6["paper"]) == ("C6", [3, 50], [0, 50])
    assert c6["verdict"] == "not shown different"  # 3 of 50 against 0 of 50: p = 0.24
    text = "\n".join(verdicts.section(tests))
    assert "| two_wheel | random | first-trial steps | 6,087 (5,789, 49) |" in text


def test_a_figure_far_from_the_paper_is_different():
    first = {"mean": 2900, "sd": 2400, "reached": 100}
    per = {"mean": 1000, "sd": 500, "seeds": 100}
    tests = verdicts.tested({"groups": [_group("two_wheel", "random", first, per,
                                               {"below_30": 10, "below_49": 40})]})
    rows = {r["figure"]: r for r in tests["figures"]}
    assert rows["first-trial steps"]["verdict"] == "different"
    assert not rows["first-trial steps"]["within_1_5x"]  # 0.48x
    assert tests["counts"][0]["verdict"] == "different"  # 10 of 100 against 43 of 50
