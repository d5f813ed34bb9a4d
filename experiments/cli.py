"""The `ebrl` command (also `python -m experiments`): robots, run, report, render, bench,
check, sweep, ablate, fit, evolve, demo.

Exit status: 0 done; 1 some runs failed (each recorded in its run.json, named by the
report, retried by a rerun); 2 a bad argument (one line, nothing written), or a results
folder that cannot be written or a lost Ray cluster (one line; finished runs kept, the same
command resumes); 130 Ctrl-C (finished runs kept; the same command resumes), SIGTERM likewise.
"""
import argparse
import os
import signal
import sys
import threading

from experiments.commands import (ablate, bench, check, demo, evolve, evolve_report, fit,
                                  maze_study, render, report, robots, rooms, run, sweep)
from experiments.commands.common import INTERRUPTED, USAGE_ERROR, fail

#: The commands in the order `ebrl --help` lists them; each module's add_parser adds its
#: sub-parser (its arguments) and sets func, its action.
COMMANDS = (robots, rooms, run, report, render, bench, check, sweep, ablate, fit, evolve,
            evolve_report, maze_study, demo)


class _Parser(argparse.ArgumentParser):
    """Bad arguments: one line on stderr and exit status 2, nothing written."""

    def error(self, message):
        self.exit(USAGE_ERROR, f"{self.prog}: error: {message}\n")


def build_parser():
    p = _Parser(prog="ebrl", description=__doc__)
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for command in COMMANDS:
        command.add_parser(sub)
    return p


def _terminated(signum, frame):
    """SIGTERM (a `kill`, a scheduler's stop) as Ctrl-C: the runner then stops its workers
    instead of leaving them to finish their runs as orphans."""
    raise KeyboardInterrupt


def main(argv=None):
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, _terminated)
    try:
        args = build_parser().parse_args(argv)
        return args.func(args)
    except ValueError as e:  # a bad map, mount or robot file found at work (runner.check)
        from experiments.running import runner
        if runner.input_error(e) is None:
            raise
        return fail(str(e))
    except KeyboardInterrupt:
        print("ebrl: interrupted; finished runs are kept, rerun to resume", file=sys.stderr)
        return INTERRUPTED
    except OSError as e:  # a disk that fills, a folder removed, a lost Ray cluster, say
        where = f": {e.filename}" if e.filename else ""
        status = fail(f"{e.strerror or e}{where}")
        if getattr(e, "exit_now", False):  # a lost Ray cluster: Ray's exit would wait on it
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(status)
        return status


if __name__ == "__main__":
    sys.exit(main())
