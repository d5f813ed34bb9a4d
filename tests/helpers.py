"""What several test files share: the repository root, and the `ebrl` command run as a
real process (python -m experiments), as a user runs it, or in this process (the same
main(), the same one line and exit status, without a second's imports per command: the
unit tier's way to check a bad input, and the slow tier's for a command that is not
killed)."""
import contextlib
import io
import os
import pathlib
import signal
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


def ebrl_here(*args, cwd=ROOT, check=False):
    """`ebrl ARGS` in this process (experiments.cli.main, in cwd, its output captured),
    as a CompletedProcess: its exit status, stdout and stderr. For commands that refuse
    their input before any work, and for whole commands whose process is neither killed
    nor given other environment variables (the test-only hooks): their runs are made in
    the pool's worker processes as ever, forked from the one forkserver this pytest
    worker starts (experiments.running.pool.context), without a second of imports per
    command. What is written to the file descriptors by native code is not captured. A
    traceback propagates as the exception it is. check as ebrl's."""
    from experiments.cli import main
    out, err = io.StringIO(), io.StringIO()
    here, handler = os.getcwd(), signal.getsignal(signal.SIGTERM)
    os.chdir(cwd)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                status = main([str(a) for a in args])
            except SystemExit as e:
                status = e.code if isinstance(e.code, int) else (0 if e.code is None else 1)
    finally:
        os.chdir(here)
        signal.signal(signal.SIGTERM, handler)
    proc = subprocess.CompletedProcess(["ebrl", *map(str, args)], status, out.getvalue(),
                                       err.getvalue())
    if check and status != 0:
        raise AssertionError(f"ebrl {args} failed:\n{proc.stdout}\n{proc.stderr}")
    return proc
