"""Property-based tests (hypothesis) of the readers of the newer surfaces (issue 50): any
map text, any mount file and any run folder gives a parsed value or our one-line error
(models.rooms.MapError, tasks.mount.MountError, results.DamagedRun), never another
exception. Inputs are drawn near the valid ones (a shipped map, the ant's and the point
mass's mounts, a written run folder) with parts changed, and as raw bytes; the example
counts are kept small, so the file runs in a few seconds."""
import functools
import json
import math
import os
import pathlib
import tempfile
import tomllib

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import run_folders
from experiments.running import results
from helpers import ROOT
from models import rooms
from tasks import mount

#: Few examples each (EBRL_PROPERTY_EXAMPLES=N for a longer search by hand), so the tests
#: stay fast; no example database (hypothesis' own cache, .hypothesis/, is git-ignored).
EXAMPLES = int(os.environ.get("EBRL_PROPERTY_EXAMPLES", "60"))
FEW = settings(max_examples=EXAMPLES, deadline=None, database=None,
               suppress_health_check=[HealthCheck.function_scoped_fixture,
                                      HealthCheck.too_slow])


def _one_line(error, path=None):
    text = str(error)
    assert text and "\n" not in text, text
    if path is not None:
        assert text.startswith(str(path)), text


# -- maps --------------------------------------------------------------------------
SUTTON = (rooms.MAP_DIR / "sutton.txt").read_text()
MAP_CHARS = "* PG#\n\r\t\ufeffcelwasx0123456789.-e"


@st.composite
def map_texts(draw):
    """A shipped map with a few characters replaced, inserted or cut, or any text."""
    if draw(st.booleans()):
        return draw(st.text(alphabet=MAP_CHARS, max_size=200))
    text = list(SUTTON)
    for _ in range(draw(st.integers(1, 4))):
        i = draw(st.integers(0, len(text) - 1))
        how = draw(st.sampled_from(["replace", "insert", "cut"]))
        char = draw(st.sampled_from(MAP_CHARS))
        if how == "replace":
            text[i] = char
        elif how == "insert":
            text.insert(i, char)
        else:
            del text[i:i + draw(st.integers(1, 40))]
    if draw(st.booleans()):
        text = list(f"# cell {draw(st.floats(allow_nan=True, allow_infinity=True))}\n") + text
    return "".join(text)


@FEW
@given(map_texts())
def test_any_map_text_is_a_map_or_one_line(text):
    try:
        m = rooms.parse(text, "map.txt")
    except rooms.MapError as e:
        _one_line(e, "map.txt")
        return
    again = rooms.parse(m.text(), "again.txt")  # a map's text reads back as itself
    assert again.rows == m.rows and again.cell == m.cell
    assert m.shortest_cells() >= 1 and rooms.merged_walls(m) is not None


@FEW
@given(st.binary(max_size=120) | map_texts().map(lambda t: t.encode("utf-8", "replace")))
def test_any_map_file_is_a_map_or_one_line(data):
    with tempfile.TemporaryDirectory() as folder:
        path = pathlib.Path(folder) / "m.txt"
        path.write_bytes(data)
        try:
            rooms.load(str(path))
        except rooms.MapError as e:
            _one_line(e)


@settings(max_examples=max(25, EXAMPLES // 2), deadline=None, database=None)
@given(st.integers(-3, 40), st.integers(-3, 40), st.integers(-2**40, 2**40))
def test_any_random_maze_name_is_a_maze_or_one_line(width, height, seed):
    try:
        m = rooms.load(f"random:{width}x{height}:{seed}")
    except rooms.MapError as e:
        _one_line(e)
        return
    assert (m.width, m.height) == (width, height)


# -- mounts ------------------------------------------------------------------------
def _toml(value):
    """A value as inline TOML (tables inline, keys quoted)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return ("nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
                if math.isinf(value) else repr(value))
    if isinstance(value, int):
        return str(value)
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False).replace("\x7f", "\\u007f")
    if isinstance(value, list):
        return "[" + ", ".join(map(_toml, value)) + "]"
    return "{" + ", ".join(f"{json.dumps(k)} = {_toml(v)}" for k, v in value.items()) + "}"


def _document(data):
    return "".join(f"{json.dumps(k)} = {_toml(v)}\n" for k, v in data.items())


def _base(name):
    """A shipped mount's table, its robot file's path made absolute (the tests' mounts lie
    elsewhere)."""
    path = ROOT / "models" / "mounts" / f"{name}.toml"
    data = tomllib.loads(path.read_text())
    if ":" not in data["file"]:
        data["file"] = str((path.parent / data["file"]).resolve())
    return data


BASES = {name: _base(name) for name in ("ant", "point_mass", "car", "gym_ant")}
SCALARS = (st.none() | st.booleans() | st.integers(-2**70, 2**70)
           | st.floats(allow_nan=True, allow_infinity=True)
           | st.text(st.characters(blacklist_categories=("Cs",)), max_size=12)
           | st.sampled_from(["", "free", "planar", "gait", "servos", "sphere", "two_wheel",
                              "stop", "nope", "front_left_hip"]))
VALUES = st.recursive(SCALARS.filter(lambda v: v is not None),
                      lambda inner: st.lists(inner, max_size=3)
                      | st.dictionaries(st.sampled_from(["kind", "swing", "lift", "x", "radius",
                                                         "frequency", "kp", "geom"]),
                                        inner, max_size=3), max_leaves=6)


def _paths(data, prefix=()):
    """Every (table path, key) in a mount's data, tables and arrays of tables included."""
    for key, value in data.items():
        yield prefix, key
        if isinstance(value, dict):
            yield from _paths(value, prefix + (key,))
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            for i, item in enumerate(value):
                yield from _paths(item, prefix + (key, i))


@st.composite
def mounts(draw):
    """A shipped mount with some fields removed, changed to any TOML value, or added."""
    base = draw(st.sampled_from(sorted(BASES)))
    data = json.loads(json.dumps(BASES[base]))
    for _ in range(draw(st.integers(1, 2))):
        where, key = draw(st.sampled_from(list(_paths(data))))
        table = data
        for step in where:
            table = table[step]
        how = draw(st.sampled_from(["remove", "change", "add"]))
        if how == "remove":
            table.pop(key, None)
        elif how == "change":
            table[key] = draw(VALUES)
        else:
            table[draw(st.sampled_from(["colour", "kp", "readings", "gait", "unit",
                                        "control_substeps", "radius", "bump", "forward",
                                        "rest"]))] = draw(VALUES)
    return _document(data)


@FEW
@given(mounts() | st.text(max_size=80))
def test_any_mount_file_is_a_mount_or_one_line_naming_the_file(text):
    with tempfile.TemporaryDirectory() as folder:
        path = pathlib.Path(folder) / "m.toml"
        path.write_text(text)
        try:
            m = mount.parse(path)
        except mount.MountError as e:
            _one_line(e, path)
            return
        assert m.path == path.resolve()


# -- run folders -------------------------------------------------------------------
@functools.cache
def _files():
    """A written run folder's files, by name (made once, when first drawn)."""
    with tempfile.TemporaryDirectory() as folder:
        made = run_folders.make(pathlib.Path(folder))
        return {p.name: p.read_bytes() for p in made.iterdir()}


JSON = st.recursive(st.none() | st.booleans() | st.integers(-2**64, 2**64)
                    | st.floats(allow_nan=True, allow_infinity=True) | st.text(max_size=8),
                    lambda inner: st.lists(inner, max_size=3)
                    | st.dictionaries(st.text(max_size=8), inner, max_size=3), max_leaves=6)


@st.composite
def records(draw):
    """The written run's run.json with a key removed or set to any JSON value."""
    run = json.loads(_files()["run.json"])
    for _ in range(draw(st.integers(1, 3))):
        table = run
        for step in draw(st.sampled_from([(), ("parameters",), ("metrics",),
                                          ("parameters", "task")])):
            table = table.get(step) if isinstance(table.get(step), dict) else table
        key = draw(st.sampled_from(sorted(table) + ["extra"]))
        if draw(st.booleans()):
            table.pop(key, None)
        else:
            table[key] = draw(JSON)
    return json.dumps(run).encode()


@st.composite
def damaged_files(draw):
    """The written run's files, one of them cut short, with bytes changed, or replaced."""
    files = dict(_files())
    name = draw(st.sampled_from(sorted(files)))
    data = bytearray(files[name])
    how = draw(st.sampled_from(["cut", "flip", "replace", "record"]))
    if how == "cut":
        data = data[:draw(st.integers(0, len(data)))]
    elif how == "flip":
        for _ in range(draw(st.integers(1, 3))):
            data[draw(st.integers(0, len(data) - 1))] ^= draw(st.integers(1, 255))
    elif how == "replace":
        data = draw(st.binary(max_size=64))
    else:
        name, data = "run.json", draw(records())
    files[name] = bytes(data)
    return files


@FEW
@given(damaged_files())
def test_any_run_folder_is_a_run_or_one_line_naming_its_folder(files):
    with tempfile.TemporaryDirectory() as folder:
        root = pathlib.Path(folder)
        run = results.run_dir(root, run_folders.spec())
        run.mkdir(parents=True)
        for name, data in files.items():
            (run / name).write_bytes(data)
        try:
            record = results.read_run(run, root)
        except results.DamagedRun as e:
            _one_line(e, run)
            assert results.existing(root, run_folders.spec()) == "damaged"
            return
        assert record["status"] in ("complete", "failed")
        if record["status"] == "complete":
            results.load_trace(root, "two_wheel", "avoidance", 0)
