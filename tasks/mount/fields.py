"""A mount file's field checks: each bad field is one line, ``<mount file>: <field>: <what
is wrong>`` (MountError)."""
import math
import pathlib
import tomllib
from typing import NoReturn


class MountError(ValueError):
    """A bad mount: one line naming the mount file and the field."""


def fail(path: pathlib.Path, field: str, message: str) -> NoReturn:
    """Raises the one-line MountError of the mount file at `path`."""
    raise MountError(f"{path}: {field}: {message}")


def read(path: pathlib.Path, text: str | None = None) -> dict:
    """The mount file's TOML as a dict (text: the file's text, read from path if None)."""
    if text is None and not path.is_file():
        raise MountError(f"no mount file at {path}")
    try:
        return tomllib.loads(path.read_text() if text is None else text)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise MountError(f"{path}: not a TOML file: {e}") from None
    except ValueError as e:  # an integer past Python's 4300 digits
        said = str(e).split(":")[0] if "Exceeds the limit" in str(e) else str(e)
        raise MountError(f"{path}: not a TOML file: {said} (an integer too long)") from None


def _finite(v) -> bool:
    """A finite float, or an integer a float holds (math.isfinite raises OverflowError
    for one past the largest float)."""
    try:
        return math.isfinite(v)
    except OverflowError:
        return False


def _shown(v) -> str:
    """A value as a line shows it: an integer past a float by its digits."""
    if isinstance(v, int) and not _finite(v):
        return f"an integer of {len(str(abs(v)))} digits"
    return repr(v)


class Fields:
    """The field checks of one mount file: each fails with MountError naming it."""

    def __init__(self, path: pathlib.Path):
        self.path = path

    def fail(self, field: str, message: str) -> NoReturn:
        fail(self.path, field, message)

    def table(self, d, keys, where: str) -> dict:
        if not isinstance(d, dict):
            self.fail(where, "must be a table")
        for k in d:
            if k not in keys:
                self.fail(f"{where}.{k}" if where else k,
                          f"unknown key; valid: {', '.join(sorted(keys))}")
        return d

    def text(self, d: dict, key: str, where: str, default=None):
        v = d.get(key, default)
        if v is default and default is None and key not in d:
            return None
        if not isinstance(v, str) or not v:
            self.fail(where, "must be a non-empty string")
        return v

    def number(self, d: dict, key: str, where: str, default=None, positive: bool = True):
        if key not in d:
            return default
        v = d[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            self.fail(where, f"must be a number, got {v!r}")
        if not _finite(v):
            self.fail(where, f"must be a finite number, got {_shown(v)}")
        if positive and v <= 0:
            self.fail(where, f"must be positive, got {v!r}")
        return float(v)

    def within(self, v, allowed, where: str):
        """v if an ebrl.readings.Range allows it, else the field's MountError saying the
        range ("must be at least 0.001, got 1e-300")."""
        if isinstance(v, int) and not isinstance(v, bool) and not _finite(v):
            self.fail(where, f"must be a finite number, got {_shown(v)}")
        problem = allowed.problem(v)
        if problem is not None:
            self.fail(where, f"{problem}, got {v!r}")
        return v

    def ranged(self, d: dict, key: str, where: str, allowed, default=None):
        """d[key] within the Range allowed, as a float (default when absent)."""
        if key not in d:
            return default
        return float(self.within(d[key], allowed, where))

    def names(self, d: dict, key: str, where: str, valid=None) -> tuple[str, ...]:
        v = d.get(key, [])
        if not isinstance(v, list) or not all(isinstance(x, str) and x for x in v):
            self.fail(where, "must be a list of strings")
        if valid is not None:
            for x in v:
                if x not in valid:
                    self.fail(where, f"unknown {x!r}; valid: {', '.join(valid)}")
        return tuple(v)
