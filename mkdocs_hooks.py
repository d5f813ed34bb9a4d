"""The docs site's hooks (mkdocs.yml `hooks:`): the site holds docs/ and the repository's
pages beside it (README.md as the home page, RESULTS.md, EVOLVE.md, CHANGELOG.md), and
every other file of the repository that a page links to (a source file, a map, the
licence), so a link works on the site as it does in the repository.

The pages are written for the repository, where `docs/running.md` links `../RESULTS.md`
and README.md links `docs/running.md`. Each relative link is resolved in the repository
and written again relative to the page's place in the site (docs/X is the site's X; a
file outside docs/ keeps its repository path). MkDocs then checks every link and
anchor as usual (mkdocs.yml's `validation`): a link to a file that does not exist, in
docs/ or outside it, fails `mkdocs build --strict`. Fenced code blocks are left as
they are.

A page's marker `<!-- ebrl help: ... -->` becomes every command's `--help`, taken from
the commands' own parsers when the site is built (docs/api/experiments.md).
"""
import argparse
import contextlib
import logging
import os
import pathlib
import posixpath
import re

from mkdocs.structure.files import File

from experiments import cli

log = logging.getLogger("mkdocs.plugins.ebrl")

#: The repository's pages outside docs/ that the site holds, by their path in the site.
PAGES = {"README.md": "index.md", "RESULTS.md": "RESULTS.md", "EVOLVE.md": "EVOLVE.md",
         "CHANGELOG.md": "CHANGELOG.md"}
#: An inline link or image, `](target` (a title after a space is left alone).
LINK = re.compile(r"(\]\()([^)\s]+)")
FENCE = re.compile(r"^\s*(```|~~~)")
#: A target that is no path in the repository: a URL, an e-mail, a page's own anchor.
ELSEWHERE = re.compile(r"^([a-zA-Z][a-zA-Z0-9+.-]*:|#|/)")

#: Where a page takes every command's help (commands_help).
HELP = re.compile(r"^<!-- ebrl help:.*-->$", re.MULTILINE)
#: The help's width, whatever the terminal that builds the site.
HELP_COLUMNS = "100"

#: Each page's path in the repository, by its path in the site (set by on_files).
_repository_paths = {}


def _root(config):
    return pathlib.Path(config.config_file_path).resolve().parent


def _docs_prefix(config):
    """docs/'s path in the repository, with a trailing slash ("docs/")."""
    return pathlib.Path(config.docs_dir).resolve().relative_to(_root(config)).as_posix() + "/"


def site_path(path, config):
    """The site's path of a file at `path` in the repository (posix, relative)."""
    prefix = _docs_prefix(config)
    if path in PAGES:
        return PAGES[path]
    return path[len(prefix):] if path.startswith(prefix) else path


def _targets(markdown):
    """(line number, line) of every line outside fenced code blocks."""
    fenced = False
    for number, line in enumerate(markdown.splitlines(keepends=True)):
        if FENCE.match(line):
            fenced = not fenced
            continue
        if not fenced:
            yield number, line


def _resolve(target, page_path):
    """(the repository path a relative link of the page at page_path names, its anchor),
    or None for a URL, an anchor of the page itself or an absolute path."""
    if ELSEWHERE.match(target):
        return None
    path, _, anchor = target.partition("#")
    return posixpath.normpath(posixpath.join(posixpath.dirname(page_path), path)), anchor


def on_files(files, config):
    """Adds the repository's pages (PAGES) and every other file outside docs/ that a page
    links to; a page outside docs/ that the site does not hold is a warning."""
    root, prefix = _root(config), _docs_prefix(config)
    _repository_paths.clear()
    for page in files.documentation_pages():
        _repository_paths[page.src_uri] = prefix + page.src_uri
    for path, src_uri in PAGES.items():
        if (root / path).is_file():
            files.append(File.generated(config, src_uri, abs_src_path=str(root / path)))
            _repository_paths[src_uri] = path
    wanted = set()
    for src_uri, page_path in list(_repository_paths.items()):
        markdown = (root / page_path).read_text(encoding="utf-8")
        for _, line in _targets(markdown):
            for match in LINK.finditer(line):
                resolved = _resolve(match.group(2), page_path)
                if resolved is None or resolved[0].startswith(("..", prefix)) or resolved[0] in PAGES:
                    continue
                if resolved[0].endswith(".md"):
                    log.warning("%s links to %s, a page outside docs/ that the site does not hold "
                                "(mkdocs_hooks.PAGES)", page_path, resolved[0])
                elif (root / resolved[0]).is_file():
                    wanted.add(resolved[0])
    for path in sorted(wanted):
        if files.get_file_from_path(path) is not None:
            log.warning("%s outside docs/ has the site path of docs/%s", path, path)
            continue
        files.append(File(path, str(root), config.site_dir, config.use_directory_urls))
    return files


def on_page_markdown(markdown, page, config, files):
    """Each relative link written again from the page's place in the site (the module's
    docstring); links that stay inside docs/ from a page of docs/ are left as written."""
    if HELP.search(markdown):
        markdown = HELP.sub(lambda _: commands_help(), markdown)
    page_path = _repository_paths.get(page.file.src_uri)
    if page_path is None:  # a page no file of the repository holds
        return markdown
    prefix = _docs_prefix(config)
    here = posixpath.dirname(page.file.src_uri)

    def written(match):
        resolved = _resolve(match.group(2), page_path)
        if resolved is None or resolved[0].startswith(".."):
            return match.group(0)  # outside the repository: MkDocs reports it
        path, anchor = resolved
        if page_path.startswith(prefix) and path.startswith(prefix):
            return match.group(0)
        target = posixpath.relpath(site_path(path, config), here or ".")
        return match.group(1) + target + ("#" + anchor if anchor else "")

    lines = markdown.splitlines(keepends=True)
    for number, line in _targets(markdown):
        lines[number] = LINK.sub(written, line)
    return "".join(lines)


@contextlib.contextmanager
def _columns(columns):
    """argparse's help at `columns` characters (it reads COLUMNS, else the terminal's)."""
    before = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = columns
    try:
        yield
    finally:
        if before is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = before


def commands_help():
    """`ebrl --help` and every command's, as Markdown: a section per command."""
    sub = argparse.ArgumentParser(prog="ebrl").add_subparsers()
    for command in cli.COMMANDS:
        command.add_parser(sub)
    with _columns(HELP_COLUMNS):
        parts = ["### `ebrl`", "", "```text", cli.build_parser().format_help().rstrip(), "```"]
        for name, parser in sub.choices.items():
            parts += ["", f"### `ebrl {name}`", "", "```text", parser.format_help().rstrip(), "```"]
    return "\n".join(parts)
