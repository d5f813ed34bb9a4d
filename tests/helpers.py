"""What several test files share: the repository root and the `ebrl` command run as a real
process (python -m experiments), as a user runs it."""
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]


def ebrl(*args, check=False, cwd=ROOT, **kw):
    """The finished process of `ebrl ARGS` (10 minutes at most); with check, an
    AssertionError carrying its output when it fails."""
    proc = subprocess.run([sys.executable, "-m", "experiments", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, timeout=600, **kw)
    if check and proc.returncode != 0:
        raise AssertionError(f"ebrl {args} failed:\n{proc.stdout}\n{proc.stderr}")
    return proc
