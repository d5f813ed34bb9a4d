"""Runs `ebrl` command lines as forked processes of one interpreter that has imported the
command once (tests/test_cli_inputs.py): each case is a real process, with its own cwd,
its own stdout and stderr (files) and its own exit status, started by fork() instead of
a fresh `python -m experiments`, which spends about a second importing MuJoCo, numba and
dm_control before it reads its arguments.

    python forked_cli.py CASES.json OUT.json

CASES.json: [[cwd, [arg, ...]], ...]; OUT.json: [[status, stdout, stderr, seconds], ...],
the seconds from fork to exit.
"""
import json
import os
import sys
import time


def run_case(cwd, args, out_path, err_path):
    """The child: the command line in cwd, its output in two files, its status as exit."""
    os.chdir(cwd)
    for fd, path in ((1, out_path), (2, err_path)):
        f = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
        os.dup2(f, fd)
        os.close(f)
    sys.argv = ["ebrl", *args]
    status = 1
    try:
        status = main(args)
    except SystemExit as e:
        status = e.code if isinstance(e.code, int) else (0 if e.code is None else 1)
    except BaseException:  # a traceback, as the real command would print it
        import traceback
        traceback.print_exc()
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(status)


if __name__ == "__main__":
    from experiments.cli import build_parser, main
    # what a command imports when it runs, imported once here: the parser's registry
    # (MuJoCo, dm_control, numba), the runner and the report
    build_parser()
    import experiments.outputs.report
    import experiments.running.runner  # noqa: F401
    cases = json.loads(open(sys.argv[1]).read())
    scratch = os.path.dirname(os.path.abspath(sys.argv[2]))
    results = []
    for i, (cwd, args) in enumerate(cases):
        out_path = os.path.join(scratch, f"case_{i:03d}.out")
        err_path = os.path.join(scratch, f"case_{i:03d}.err")
        started = time.perf_counter()
        pid = os.fork()
        if pid == 0:
            run_case(cwd, args, out_path, err_path)
        _, wait_status = os.waitpid(pid, 0)
        seconds = time.perf_counter() - started
        with open(out_path) as o, open(err_path) as e:
            results.append([os.waitstatus_to_exitcode(wait_status), o.read(), e.read(),
                            seconds])
    with open(sys.argv[2], "w") as f:
        json.dump(results, f)
