"""The tests of experiments.outputs.verdicts as REPORT.md's and RESULTS.md's tables: the
figures, the shrinks, the counts (C5, C6) and the claims, each p raw and Holm-adjusted."""
from experiments.outputs import verdicts


def p_text(p):
    """A p value as the tables print it ("-" for none, "<0.001" below it)."""
    return "-" if p is None else ("<0.001" if p < 0.001 else f"{p:.3f}")


def _f(v, digits=0):
    return "-" if v is None else f"{v:,.{digits}f}"


def _yes(v):
    return "-" if v is None else ("yes" if v else "no")


def figures_table(tests):
    lines = ["| robot | condition | figure | paper mean (sd, n) | ours mean (sd, n) | ours / paper "
             "| within 1.5x | Welch p (Holm) | TOST p (Holm) | TOST power | verdict |",
             "|---|---|---|---:|---:|---:|:-:|---:|---:|---:|---|"]
    for r in tests["figures"]:
        p, o = r["paper"], r["ours"]
        lines.append(f"| {r['robot']} | {r['condition']} | {r['figure']} "
                     f"| {_f(p['mean'])} ({_f(p['sd'])}, {p['n']}) "
                     f"| {_f(o['mean'])} ({_f(o['sd'])}, {o['n']}) | {_f(r['ratio'], 2)} "
                     f"| {_yes(r['within_1_5x'])} "
                     f"| {p_text(r['difference_p'])} ({p_text(r['difference_p_holm'])}) "
                     f"| {p_text(r['equivalence_p'])} ({p_text(r['equivalence_p_holm'])}) "
                     f"| {_f(r['power'], 2)} | {r['verdict']} |")
    return "\n".join(lines)


def shrinks_table(tests):
    sens = tests["rho_sensitivity"]
    lines = [f"| robot | condition | paper (log se) | ours (log se) | ours 95% CI | ours / paper "
             f"| within 1.5x | z p (Holm) | equivalence p (Holm) | power | verdict "
             f"| verdict at rho {sens:g} |", "|---|---|---:|---:|---|---:|:-:|---:|---:|---:|---|---|"]
    for r in tests["shrinks"]:
        ci = "-" if r["ci95"] is None else f"[{r['ci95'][0]:.2f}, {r['ci95'][1]:.2f}]"
        lines.append(f"| {r['robot']} | {r['condition']} | {r['paper']:.2f} ({r['paper_se']:.3f}) "
                     f"| {r['ours']:.2f} ({_f(r['ours_se'], 3)}) | {ci} | {r['ratio']:.2f} "
                     f"| {_yes(r['within_1_5x'])} "
                     f"| {p_text(r['difference_p'])} ({p_text(r['difference_p_holm'])}) "
                     f"| {p_text(r['equivalence_p'])} ({p_text(r['equivalence_p_holm'])}) "
                     f"| {_f(r['power'], 2)} | {r['verdict']} | {r['sensitivity']['verdict']} |")
    return "\n".join(lines)


def counts_table(tests):
    lines = ["| claim | robot | condition | runs below | paper | ours | test | p (Holm) "
             "| Fisher p | verdict |", "|---|---|---|---:|---:|---:|---|---:|---:|---|"]
    for r in tests["counts"]:
        lines.append(f"| {r['claim']} | {r['robot']} | {r['condition']} | {r['bar']} goals "
                     f"| {r['paper'][0]}/{r['paper'][1]} | {r['ours'][0]}/{r['ours'][1]} "
                     f"| {r['test']} | {p_text(r['p'])} ({p_text(r['p_holm'])}) "
                     f"| {p_text(r['fisher_p'])} | {r['verdict']} |")
    return "\n".join(lines)


def claims_table(claims):
    """The qualitative claims (verdicts.claim_tests' rows), each with its test."""
    lines = ["| claim | ours | test | p (Holm) | holds |", "|---|---|---|---:|:-:|"]
    for c in claims:
        holm = "" if c["p_holm"] is None else f" ({p_text(c['p_holm'])})"
        lines.append(f"| {c['claim']} | {c['ours']} | {c['test']} | {p_text(c['p'])}{holm} "
                     f"| {'yes' if c['holds'] else 'no'} |")
    return "\n".join(lines)


def tally_text(tests):
    """The verdicts counted, raw and by Holm: one sentence."""
    t = verdicts.tally(tests)
    raw = ", ".join(f"{t[k]} {k}" for k in verdicts.VERDICTS)
    holm = ", ".join(f"{t['holm'][k]} {k}" for k in verdicts.VERDICTS)
    weak = [f"{r['robot']} {r['condition']} {r['figure']}" for r in tests["figures"]
            if r.get("power_holm_step") is not None and r["power_holm_step"] < 0.8]
    out = (f"Of {t['tested']} (figures and shrinks): {raw} (raw p); family-wise, by Holm's "
           f"p: {holm}; {t['within_1_5x']} within 1.5x (the point alone, not a test).")
    if weak:
        out += (" Family-wise equivalence is out of reach (TOST power below 0.8 at Holm's "
                "strictest step, alpha / the family's size) for: " + "; ".join(weak) + ".")
    return out


def section(tests, heading="##"):
    """REPORT.md's (and RESULTS.md's) lines: the tables with the rules that made them
    (docs/interpretation.md, "Testing the figures (protocol 8)")."""
    fam = tests["families"]
    sizes = ", ".join(f"{k} {v['tests']}" for k, v in fam.items())
    return [f"{heading} The figures tested against the paper", "",
            f"Each figure: Welch's test (two-sided, difference) and an equivalence test (two "
            f"one-sided Welch tests, margin {verdicts.LOW:.3g}x-{verdicts.HIGH:.3g}x the "
            f"paper's mean) at alpha {tests['alpha']}, from the paper's mean, sd and n and "
            f"ours. Verdicts from the raw p: equivalent, different, equivalent and different "
            f"(both reject), undecided (neither; the TOST power, by simulation from a gamma "
            f"with the paper's mean and sd, says how weak that is). Holm-adjusted p in "
            f"brackets, within each family (tests: {sizes}). {tally_text(tests)}", "",
            figures_table(tests), "",
            f"The shrinks (steps per trial / first trial), on the log scale by z tests with "
            f"both samples' error: ours from our bootstrap interval, the paper's from its "
            f"own sds and n with rho {tests['rho']:g} (its unreported correlation of a run's "
            f"first trial and steps per trial; the last column at rho "
            f"{tests['rho_sensitivity']:g}):", "",
            shrinks_table(tests), "",
            "C5 and C6 as counts of runs (C5: Fisher's exact test, two-sided; C6: the rank "
            "test, as 49 goals is the paper's own worst run, Fisher's beside it):", "",
            counts_table(tests), ""]
