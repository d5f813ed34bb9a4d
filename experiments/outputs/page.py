"""The one editor of the pages the tool writes into (RESULTS.md, README.md, a user's own
page given as --results): a block of generated lines between a start and an end marker
of its own (an HTML comment each), everything else on the page kept byte for byte.

The markers are parsed strictly before anything is written: a page that is not UTF-8
text, a start marker without its end, an end before its start, a marker given twice, or
another block's marker inside this block's is refused with PageError, one line naming
the page and the line ("RESULTS.md: line 12: ..."). Commands check their pages before any
work (`check`), and again when they write (`replace`), which writes the new page beside
the old one and renames it over it (experiments.running.disk.atomic_file): the page is
either its old self or the new one, never half of either.
"""
import pathlib
import re

from experiments.running import results

#: A marker of any of the tool's blocks (ebrl report, ebrl headline, ebrl ablate, ebrl
#: fit, ebrl evolve-report, ebrl multiverse, maze-study): one block's edit must never
#: take another's.
ANY_MARKER = re.compile(r"<!--\s*(?:ebrl\b|maze-study:)[^\n]*?-->")


class PageError(ValueError, results.ResultsError):
    """A page the tool cannot edit safely: one line naming the page and the line. A
    ValueError for the checks before any work, a ResultsError for the commands' writes
    (each ends the command with its one line)."""


def _line(text, offset):
    return text.count("\n", 0, offset) + 1


def read(path):
    """The page's text (its newlines as they are), None when there is no page;
    PageError when it cannot be read or is not UTF-8 text."""
    path = pathlib.Path(path)
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        return None
    except IsADirectoryError:
        raise PageError(f"{path}: is a folder, not a page") from None
    except OSError as e:
        raise PageError(f"{path}: cannot be read ({e.strerror or e})") from None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as e:
        line = data.count(b"\n", 0, e.start) + 1
        raise PageError(f"{path}: line {line}: not UTF-8 text (byte {data[e.start]:#04x}); "
                        "the page is left as it is") from None


def _positions(text, marker):
    out, at = [], text.find(marker)
    while at >= 0:
        out.append(at)
        at = text.find(marker, at + len(marker))
    return out


def find(text, begin, end, where="the page"):
    """(start, stop): text[start:stop] is the block from its start marker through its end
    marker; None when the page has neither marker. PageError (naming `where` and the
    line) for a lone, doubled or misordered marker, or another block's marker inside."""
    begins, ends = _positions(text, begin), _positions(text, end)
    if not begins and not ends:
        return None
    for found, marker in ((begins, begin), (ends, end)):
        if len(found) > 1:
            raise PageError(f"{where}: line {_line(text, found[1])}: a second {marker} "
                            f"(the first is on line {_line(text, found[0])}); leave one")
    if not ends:
        raise PageError(f"{where}: line {_line(text, begins[0])}: {begin} has no {end} "
                        "after it; add the end marker where the block ends")
    if not begins:
        raise PageError(f"{where}: line {_line(text, ends[0])}: {end} without its start "
                        f"marker {begin}; add the start marker where the block begins")
    start, stop = begins[0], ends[0]
    if stop < start:
        raise PageError(f"{where}: line {_line(text, stop)}: {end} comes before its start "
                        f"marker {begin} (line {_line(text, start)}); put them in order")
    inner = start + len(begin)
    for m in ANY_MARKER.finditer(text, inner, stop):
        raise PageError(f"{where}: line {_line(text, m.start())}: another block's marker "
                        f"{m.group()} lies inside the block {begin} ... {end} "
                        f"(lines {_line(text, start)}-{_line(text, stop)}); move it out")
    return start, stop + len(end)


def edited(text, begin, end, lines, where="the page"):
    """The page's text with the block replaced by `lines` (which start with begin and end
    with end), everything outside it as it was; a page without the block gets it at its
    end. PageError as find's."""
    lines = list(lines)
    if lines[:1] != [begin] or lines[-1:] != [end]:
        raise ValueError("a block's lines start with its start marker and end with its end")
    span = find(text, begin, end, where)
    # the page's own line ends, from the text outside the block (the block is ours)
    outside = text if span is None else text[:span[0]] + text[span[1]:]
    # (a page that ends in a bare CR, the block appended after it, gets CRLF: the CR and
    # the appended LF make one)
    crlf = "\r\n" in outside or (span is None and outside.endswith("\r"))
    newline = "\r\n" if crlf else "\n"
    body = newline.join(lines)
    if span is not None:
        return text[:span[0]] + body + text[span[1]:]
    gap = ("" if not text or text.endswith(2 * newline)
           else newline if text.endswith(newline) else 2 * newline)
    return text + gap + body + newline


def check(path, begin, end, option=None):
    """Before any work: the page at path (if any) can take the block; PageError if not.
    option, e.g. "--results", is named before the page."""
    path = pathlib.Path(path)
    where = f"{option} {path}" if option else str(path)
    try:
        text = read(path)
    except PageError as e:
        raise PageError(f"{option} {e}" if option else str(e)) from None
    if text is not None:
        find(text, begin, end, where)


def has_block(path, begin, end):
    """Whether the page at path holds the block (PageError for a broken one, as check)."""
    text = read(path)
    return text is not None and find(text, begin, end, str(path)) is not None


def replace(path, begin, end, lines, title="# Results"):
    """Writes `lines` as the page's block (edited), the rest of the page kept; a missing
    page is made, titled. The new page is written beside the old one and renamed over it;
    PageError (nothing written) for a page the block cannot go in."""
    path = pathlib.Path(path)
    text = read(path)
    if text is None:
        text = f"{title}\n\n" if title else ""
    results.atomic_write(path, edited(text, begin, end, lines, str(path)).encode("utf-8"))
    return path
