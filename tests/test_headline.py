"""The headline of README.md and RESULTS.md (experiments.outputs.headline): generated from
the committed summaries, never typed, and written by `ebrl report --literal`."""
import json

import pytest

import helpers
from experiments.outputs import headline
from helpers import ROOT, ebrl_here


def _committed():
    current = json.loads((ROOT / "summary.json").read_text())
    literal = json.loads((ROOT / headline.LITERAL_SUMMARY).read_text())
    return current, literal


def test_the_pages_headline_is_the_committed_summaries():
    text = "\n".join(headline.block(*_committed()))
    for page in ("README.md", "RESULTS.md"):
        assert text in (ROOT / page).read_text(), (
            f"{page}'s headline is not summary.json's: rerun `ebrl report results --results "
            f"RESULTS.md --literal results-literal` (docs/running.md)")


def test_the_headline_rows_carry_the_papers_figures_and_both_protocols():
    current, literal = _committed()
    rows = headline.rows(current, literal)
    assert len(rows) == 12  # 8 tested figures and 4 shrinks
    first = rows[0]
    assert first[:4] == ("two_wheel", "random", "first-trial steps", "6,087 (5,789, 49)")
    assert first[4]["ours"]["mean"] == next(
        g for g in literal["groups"] if (g["robot"], g["condition"]) == ("two_wheel", "random")
    )["first_trial_steps"]["mean"]


@pytest.mark.parametrize("args,message", [
    (["--literal", "x"], "--literal needs --results"),
    (["--results", "{tmp}/R.md", "--literal", "{tmp}"], "no summary.json there"),
    (["--section", "x"], "--section needs --results"),
    (["--results", "{tmp}/R.md", "--section", " "], "--section: give the block a name"),
])
def test_literal_refusals(tmp_path, args, message):
    made = tmp_path / "made"
    made.mkdir()
    (made / "summary.json").write_text("{}")
    args = [a.format(tmp=tmp_path) for a in args]
    proc = ebrl_here("report", made, *args)
    assert proc.returncode == 2 and message in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1


@pytest.mark.slow
def test_report_literal_writes_the_headline_into_the_page_and_its_readme(tmp_path):
    out = tmp_path / "results"
    helpers.ebrl_here("run", "--robot", "two_wheel", "--condition", "all", "--seeds", "0-1",
                      "--steps", "300", "--workers", "1", "--no-progress", "--out", out, check=True)
    page, readme = tmp_path / "site" / "RESULTS.md", tmp_path / "site" / "README.md"
    page.parent.mkdir()
    from experiments.outputs import report
    page.write_text(f"# top\n\n{headline.BEGIN}\nold\n{headline.END}\n\n"
                    f"{report.BEGIN}\n{report.END}\nkept\n")
    readme.write_text(f"# top\n\n{headline.BEGIN}\nold\n{headline.END}\n\nkept\n")
    helpers.ebrl_here("report", out, "--results", page, "--figures", tmp_path / "figs",
                      "--literal", out, check=True)
    summary = json.loads((out / "summary.json").read_text())
    text = "\n".join(headline.block(summary, summary))
    for p in (page, readme):
        body = p.read_text()
        assert text in body and "\nold\n" not in body and body.endswith("kept\n")
    assert json.loads((page.parent / headline.LITERAL_SUMMARY).read_text()) == summary
    # A named section of the same page: its own block and summary, the rest kept.
    before = page.read_text()
    (tmp_path / "figs" / "first_vs_learned.png").write_bytes(b"the main block's")
    helpers.ebrl_here("report", out, "--results", page, "--figures", tmp_path / "figs",
                      "--section", "The 3D robots", check=True)
    body = page.read_text()
    begin, end = report.markers("The 3D robots")
    assert body.startswith(before) and body.count(begin) == body.count(end) == 1
    assert "| two_wheel | random | first-trial steps |" in body.split(begin)[1].split(end)[0]
    assert json.loads((page.parent / "summary-the-3d-robots.json").read_text()) == summary
    # it copies only the figures it shows: the main block's are left as they were
    assert (tmp_path / "figs" / "first_vs_learned.png").read_bytes() == b"the main block's"


def _section(text, heading):
    """The text of RESULTS.md's section `heading` (to the next "## ")."""
    rest = text.split(f"\n## {heading}\n", 1)[1]
    return rest.split("\n## ", 1)[0]


def test_the_results_prose_quotes_only_numbers_of_the_generated_blocks():
    """No figure typed by hand: a number of two or more digits in the prose of RESULTS.md's
    answer and results sections is one of the page's generated blocks."""
    import re

    from experiments.outputs import report
    text = (ROOT / "RESULTS.md").read_text()
    generated = "".join(part.split(end, 1)[0] for begin, end in
                        ((headline.BEGIN, headline.END), (report.BEGIN, report.END))
                        for part in text.split(begin)[1:])
    assert generated.strip()
    results = re.search(r"\n## (Results \(protocol \d+, seeds [\d-]+\))\n", text).group(1)
    for heading in ("The answer", results):
        prose = _section(text, heading)
        for begin, end in ((headline.BEGIN, headline.END), (report.BEGIN, report.END)):
            if begin in prose:
                prose = prose.split(begin)[0] + prose.split(end, 1)[1]
        for number in re.findall(r"\d[\d,]*(?:\.\d+)?", prose):
            if len(number.replace(",", "").replace(".", "")) >= 2:
                assert number in generated, f"RESULTS.md, {heading}: {number} is typed, not generated"


def test_a_history_page_shows_its_own_figures():
    """`ebrl report --results` rewrites docs/figures/ under the current protocol, so a page of
    docs/history/ embeds its own copies (docs/history/figures/), never docs/figures/; and
    every image a page embeds exists."""
    import re
    pages = [ROOT / "RESULTS.md", ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
    for page in pages:
        for target in re.findall(r"!\[[^\]]*\]\(([^)\s]+)\)", page.read_text()):
            if "://" in target:
                continue
            path = (page.parent / target).resolve()
            assert path.is_file(), f"{page.relative_to(ROOT)}: no image at {target}"
            if "history" in page.relative_to(ROOT).parts:
                assert (ROOT / "docs" / "history") in path.parents, \
                    f"{page.relative_to(ROOT)} shows {target}, which ebrl report rewrites"


def test_the_headline_of_the_committed_summaries_judged_by_the_current_tests():
    """The headline's format on the committed runs re-judged by today's tests
    (verdicts.tested, docs/interpretation.md "Testing the figures (protocol 8)"), whatever
    judge wrote their "tests": 12 rows, each verdict one of the four, Holm's counts beside
    the raw ones, C6 by the rank test."""
    from experiments.outputs import verdicts
    current, literal = _committed()
    for summary in (current, literal):
        summary["tests"] = verdicts.tested(summary)
    rows = headline.rows(current, literal)
    assert len(rows) == 12 and all(r[6] in verdicts.VERDICTS for r in rows)
    text = "\n".join(headline.table(current, literal))
    assert "family-wise by Holm" in text and "C6" in text and "rank (one-sided)" in text
