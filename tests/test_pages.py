"""The pages the tool writes into (issue 58): one editor (experiments.outputs.page) that
parses a block's markers strictly and writes beside, then renames. A property test: any
text with any markers in any order is either refused with one line naming the page and
the line, or edited inside its own block alone, every byte outside it kept. Then `ebrl
report --results/--section/--literal` and `maze-study --results` on broken pages, bad
section names and damaged summaries, in this process (helpers.ebrl_here) on a results
folder written without running (tests/run_folders.py): exit status 2, one line, and the
page, the results folder and the figures folder as they were."""
import hashlib
import json
import os
import pathlib
import shutil

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import run_folders
from experiments.outputs import headline, page, report
from helpers import ebrl, ebrl_here

EXAMPLES = int(os.environ.get("EBRL_PROPERTY_EXAMPLES", "200"))
MANY = settings(max_examples=EXAMPLES, deadline=None, database=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture])

BEGIN, END = report.BEGIN, report.END
OTHERS = [headline.BEGIN, headline.END, *report.markers("Other"),
          "<!-- maze-study:begin -->", "<!-- maze-study:end -->"]


# -- the editor, by property ---------------------------------------------------------
#: Page text without markers: any characters but '<' (so no marker forms by chance),
#: newlines of both kinds included.
PLAIN = st.text(st.characters(blacklist_characters="<", blacklist_categories=("Cs",)),
                max_size=20)
FRAGMENT = st.one_of(PLAIN, PLAIN, st.just("\n"), st.just("\r\n"), st.just(BEGIN),
                     st.just(END), st.sampled_from(OTHERS))


def _expected(fragments):
    """The oracle, from the fragments alone: (prefix, suffix) kept around the block, or
    None where the page must be refused."""
    ours = [i for i, f in enumerate(fragments) if f in (BEGIN, END)]
    if not ours:
        return "".join(fragments), None  # no block: appended after the whole text
    kinds = [fragments[i] for i in ours]
    if kinds != [BEGIN, END]:
        return None  # lone, doubled or misordered
    b, e = ours
    if any(f in OTHERS for f in fragments[b + 1:e]):
        return None  # another block's marker inside
    return "".join(fragments[:b]), "".join(fragments[e + 1:])


@MANY
@given(st.lists(FRAGMENT, max_size=12), st.lists(PLAIN, max_size=3))
def test_the_editor_changes_nothing_outside_its_own_block(fragments, body):
    text = "".join(fragments)
    lines = [BEGIN, *body, END]
    expected = _expected(fragments)
    if expected is None:
        with pytest.raises(page.PageError) as e:
            page.edited(text, BEGIN, END, lines, "P.md")
        message = str(e.value)
        assert message.startswith("P.md: line ") and "\n" not in message, message
        line = int(message.split("line ")[1].split(":")[0])
        assert 1 <= line <= text.count("\n") + 1
        return
    out = page.edited(text, BEGIN, END, lines, "P.md")
    prefix, suffix = expected
    outside = prefix + (suffix or "")
    newline = "\r\n" if "\r\n" in outside or (suffix is None and prefix.endswith("\r")) \
        else "\n"
    assert out.startswith(prefix) and out.endswith(suffix or "")
    assert newline.join(lines) in out[len(prefix):]
    again = page.edited(out, BEGIN, END, lines, "P.md")  # a second edit: the same page
    assert again == out


@MANY
@given(st.binary(max_size=200), st.booleans())
def test_any_bytes_are_edited_or_refused_and_a_refused_page_is_unchanged(tmp_path_factory,
                                                                         data, block):
    path = tmp_path_factory.mktemp("page") / "P.md"
    if block:
        data = data + f"\n{BEGIN}\nold\n{END}\n".encode() + data
    path.write_bytes(data)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        text = None
    lines = [BEGIN, "new", END]
    try:
        page.replace(path, BEGIN, END, lines)
    except page.PageError as e:
        assert str(e).startswith(f"{path}: line ") and "\n" not in str(e)
        assert path.read_bytes() == data
        return
    assert text is not None
    written = path.read_bytes().decode("utf-8")
    assert written == page.edited(text, BEGIN, END, lines)
    assert [p.name for p in path.parent.iterdir()] == ["P.md"]  # nothing left beside


CASES = [  # (the page, the line said)
    (f"# mine\n\n{BEGIN}\nmy text after\nmore\n", f"line 3: {BEGIN} has no {END} after it"),
    (f"a\n{END}\nb\n{BEGIN}\n", f"line 2: {END} comes before its start marker"),
    (f"a\n{END}\nb\n", f"line 2: {END} without its start marker"),
    (f"{BEGIN}\n{END}\n{BEGIN}\n{END}\n", f"line 3: a second {BEGIN} (the first is on line 1)"),
    (f"{BEGIN}\n{headline.BEGIN}\n{END}\n", "line 2: another block's marker"),
    ("caf\xe9\n".encode("latin-1"), "line 1: not UTF-8 text (byte 0xe9)"),
]


# -- ebrl report on pages, sections and summaries ------------------------------------------
@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """A results folder of four complete runs (written, not run), reported once."""
    root = tmp_path_factory.mktemp("made") / "results"
    for condition in ("random", "avoidance"):
        for seed in (0, 1):
            run_folders.make(root, run_folders.spec(seed, condition))
    ebrl_here("report", root, check=True)
    return root


def _tree(folder):
    """Every file under folder with its digest: what a refusal must leave as it was."""
    return {p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(pathlib.Path(folder).rglob("*")) if p.is_file()}


def _refused(proc, *said):
    assert proc.returncode == 2, (proc.returncode, proc.stdout, proc.stderr)
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("ebrl"), proc.stderr
    assert all(s in lines[0] for s in said), lines[0]
    assert "Traceback" not in proc.stderr and proc.stdout == ""


@pytest.fixture
def site(tmp_path, made):
    """(a copy of the results folder, the folder a page goes in): the refusals' playground."""
    root = tmp_path / "results"
    shutil.copytree(made, root)
    (tmp_path / "site").mkdir()
    return root, tmp_path / "site"


@pytest.mark.parametrize("text, said", CASES, ids=[c[1][:40] for c in CASES])
def test_report_refuses_a_broken_page_before_anything_is_written(site, text, said):
    root, folder = site
    path = folder / "RESULTS.md"
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    before, page_before = _tree(root), _tree(folder)
    proc = ebrl_here("report", root, "--results", path, "--figures", folder / "figures")
    _refused(proc, f"--results {path}: {said}")
    assert _tree(root) == before and _tree(folder) == page_before  # no figures, no summary


@pytest.mark.parametrize("text, said", CASES[:2], ids=["lone start", "end first"])
def test_maze_study_refuses_a_broken_page_before_any_run(tmp_path, text, said):
    path = tmp_path / "RESULTS.md"
    path.write_text(text.replace(BEGIN, "<!-- maze-study:begin -->")
                    .replace(END, "<!-- maze-study:end -->"))
    before = path.read_bytes()
    proc = ebrl_here("maze-study", "--sizes", "3x3", "--mazes", "1", "--seeds", "1",
                     "--results", path, "--figures", tmp_path / "figures", "--out",
                     tmp_path / "mazes", cwd=tmp_path)
    _refused(proc, f"--results {path}: line ")
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["RESULTS.md"]


def _blocks():
    from experiments.outputs import multiverse_report
    from experiments.studies import ablation, evolved, fit
    return {"ablate": (ablation.ABLATION_BEGIN, ablation.ABLATION_END),
            "fit": (fit.FIT_BEGIN, fit.FIT_END), "evolve-report": (evolved.BEGIN, evolved.END),
            "multiverse": multiverse_report.BLOCK}


@pytest.mark.parametrize("command", ["ablate", "fit", "evolve-report", "multiverse"])
def test_every_command_with_results_refuses_a_broken_page_before_any_work(tmp_path, command):
    begin, end = _blocks()[command]
    path = tmp_path / "RESULTS.md"
    path.write_text(f"# mine\n\n{begin}\nmine, after a lone start marker\n")
    before = path.read_bytes()
    for name in ("hand", "evolve", "evolved"):
        (tmp_path / name).mkdir()
    extra = {"ablate": ["--seeds", "1", "--steps", "5"],
             "fit": ["--trials", "1", "--figures", "figures"],
             "evolve-report": ["--hand", "hand", "--evolve", "evolve", "--evolved", "evolved",
                               "--figures", "figures"],
             "multiverse": ["--universes", "1", "--seeds", "0", "--steps", "5", "--figures",
                            "figures"]}[command]
    out = "EVOLVE.md" if command == "evolve-report" else "out"
    proc = ebrl_here(command, *extra, "--results", path, "--out", out, cwd=tmp_path)
    _refused(proc, f"--results {path}: line 3: {begin} has no {end} after it")
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["RESULTS.md", "evolve", "evolved",
                                                            "hand"]


def test_a_page_is_edited_in_its_block_alone_its_crlf_and_its_text_kept(site):
    root, folder = site
    path = folder / "RESULTS.md"
    head, tail = "# Mine\r\nmy words\r\n\r\n", "\r\nkept <b>bold</b>\r\n"
    path.write_bytes(f"{head}{BEGIN}\r\nold\r\n{END}{tail}".encode())
    ebrl_here("report", root, "--results", path, "--figures", folder / "figures", check=True)
    text = path.read_bytes().decode()
    assert text.startswith(head + BEGIN) and text.endswith(END + tail) and "\nold" not in text
    assert json.loads((folder / "summary.json").read_text()) == \
        json.loads((root / "summary.json").read_text())


SECTIONS = [  # (name, what the line says)
    ("!!!", "not a block's name"),
    ("a-->b", "not a block's name"),
    ("a--b", "not a block's name"),
    ("Run A ", "not a block's name"),
    ("x" * 61, "not a block's name"),
    ("résumé", "not a block's name"),
    ("literal", "its file summary-literal.json is the headline's"),
    ("Literal.", "its file summary-literal.json is the headline's"),
]


@pytest.mark.parametrize("name, said", SECTIONS, ids=[s[0][:12] for s in SECTIONS])
def test_a_section_name_that_cannot_stand_in_a_marker_or_a_file_name_is_refused(site, name,
                                                                                said):
    root, folder = site
    path = folder / "RESULTS.md"
    path.write_text("# mine\n")
    proc = ebrl_here("report", root, "--results", path, "--figures", folder / "figures",
                     "--section", name)
    _refused(proc, f"--section {name!r}: {said}")
    assert sorted(p.name for p in folder.iterdir()) == ["RESULTS.md"]


def test_two_section_names_that_share_a_file_are_refused_naming_the_clash(site):
    root, folder = site
    path = folder / "RESULTS.md"
    args = ["report", root, "--results", path, "--figures", folder / "figures"]
    ebrl_here(*args, "--section", "Run A", check=True)
    assert (folder / "summary-run-a.json").exists()
    before = _tree(folder)
    proc = ebrl_here(*args, "--section", "run a")
    _refused(proc, "--section 'run a'", "the section 'Run A'", "summary-run-a.json")
    assert _tree(folder) == before
    ebrl_here(*args, "--section", "Run A", check=True)  # the same name: its own block again
    assert path.read_text().count(report.markers("Run A")[0]) == 1
    ebrl_here(*args, "--section", "Run B", check=True)  # another: a block and a file of its own
    assert (folder / "summary-run-b.json").exists()


def _literal(tmp_path, content):
    folder = tmp_path / "literal"
    folder.mkdir()
    (folder / "summary.json").write_bytes(content)
    return folder


LITERALS = [  # (summary.json's bytes, what the line says)
    (b"{not json", "summary.json is not JSON (JSONDecodeError)"),
    (b"\xff\xfe", "summary.json is not JSON (UnicodeDecodeError)"),
    (b"[]", "summary.json: it holds a list, not a summary"),
    (b"{}", "summary.json: groups is missing"),
    (b'{"groups": [], "provenance": {"protocol_versions": [7], "commits": [], "groups": []}, '
     b'"tests": {"figures": [{"robot": "two_wheel", "condition": "random"}], "shrinks": [], '
     b'"counts": []}}', "cannot give the headline (KeyError"),
]


@pytest.mark.parametrize("content, said", LITERALS, ids=[c[1][:30] for c in LITERALS])
def test_a_damaged_literal_summary_is_one_line_before_anything_is_written(site, content, said):
    root, folder = site
    literal = _literal(folder.parent, content)
    path = folder / "RESULTS.md"
    path.write_text(f"# mine\n\n{headline.BEGIN}\nold\n{headline.END}\n")
    before, page_before = _tree(root), _tree(folder)
    proc = ebrl_here("report", root, "--results", path, "--figures", folder / "figures",
                     "--literal", literal)
    _refused(proc, f"--literal {literal}: ", said)
    assert _tree(root) == before and _tree(folder) == page_before


def test_a_broken_headline_block_in_the_readme_beside_is_refused(site):
    root, folder = site
    path, readme = folder / "RESULTS.md", folder / "README.md"
    path.write_text(f"# mine\n\n{headline.BEGIN}\nold\n{headline.END}\n")
    readme.write_text(f"# readme\n{headline.END}\nmine\n{headline.BEGIN}\n")
    before = _tree(folder)
    proc = ebrl_here("report", root, "--results", path, "--figures", folder / "figures",
                     "--literal", root)
    _refused(proc, f"{readme}: line 2: {headline.END} comes before its start marker")
    assert _tree(folder) == before


@pytest.mark.slow
def test_a_lone_marker_as_a_user_meets_it_a_real_process(site):
    """The worst case of the issue, as a user runs it: a page with a start marker and no
    end; the page is kept whole and the line names it."""
    root, folder = site
    path = folder / "RESULTS.md"
    path.write_text(CASES[0][0])
    proc = ebrl("report", root, "--results", path, "--figures", folder / "figures")
    _refused(proc, f"--results {path}: {CASES[0][1]}")
    assert path.read_text() == CASES[0][0]
