"""A running command's processes, read from /proc (Linux): what the soak and the tests of
kills and Ctrl-C use to find the local pool's workers of an `ebrl` command."""
import os
import pathlib


def children(pid):
    """The live (not zombie) processes whose parent is pid, as pid -> command line."""
    found = {}
    for entry in pathlib.Path("/proc").iterdir():
        try:
            stat = (entry / "stat").read_text()
            state, ppid = stat.rsplit(")", 1)[1].split()[:2]
            if int(ppid) == pid and state != "Z":
                found[int(entry.name)] = (entry / "cmdline").read_bytes().replace(b"\0", b" ")
        except (OSError, ValueError):
            continue
    return found


def alive(pid):
    """Whether process pid exists and is not a zombie."""
    try:
        state = pathlib.Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def pool_workers(pid):
    """The live worker processes of the local pool of the command at pid, as pid -> command
    line: the children of its forkserver (experiments.running.pool.context), or its
    spawned children where the platform has no forkserver."""
    mine = children(pid)
    servers = [p for p, cmd in mine.items() if b"multiprocessing.forkserver" in cmd]
    workers = {p: cmd for p, cmd in mine.items() if b"spawn_main" in cmd}
    for server in servers:
        workers.update(children(server))
    return workers


def cpu_seconds(pid):
    """The CPU time (user + system, in seconds) process pid has used; None once it is gone."""
    try:
        fields = pathlib.Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return None
