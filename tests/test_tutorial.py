"""docs/tutorial.py runs as a user runs it, and docs/tutorial.ipynb is the same notebook
(jupytext's pairing), committed without outputs: the tutorial cannot rot."""
import json
import os
import re
import subprocess
import sys
import time

import numpy as np
import pytest

from helpers import ROOT

#: The slow tier (pyproject.toml's markers): the tutorial run as a process.
pytestmark = pytest.mark.slow

jupytext = pytest.importorskip("jupytext")  # the test extra's (make test installs it)
SCRIPT, NOTEBOOK = ROOT / "docs" / "tutorial.py", ROOT / "docs" / "tutorial.ipynb"


def test_the_notebook_is_the_script_without_outputs():
    script, notebook = jupytext.read(SCRIPT), jupytext.read(NOTEBOOK)
    pairs = list(zip(script.cells, notebook.cells))
    assert len(script.cells) == len(notebook.cells) > 10
    for a, b in pairs:
        assert (a.cell_type, a.source) == (b.cell_type, b.source), \
            "docs/tutorial.py and .ipynb differ: run jupytext --sync docs/tutorial.py"
    assert notebook.metadata["jupytext"]["formats"] == "ipynb,py:percent"
    raw = json.loads(NOTEBOOK.read_text())
    for cell in raw["cells"]:
        if cell["cell_type"] == "code":
            assert cell["outputs"] == [] and cell["execution_count"] is None, \
                "commit the notebook without outputs"
    assert NOTEBOOK.stat().st_size < 50_000


def test_the_tutorial_runs_and_draws(tmp_path):
    import imageio.v3 as iio
    env = dict(os.environ, MPLBACKEND="Agg", EBRL_TUTORIAL_OUT=str(tmp_path))
    started = time.perf_counter()
    proc = subprocess.run([sys.executable, str(SCRIPT)], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=300)
    seconds = time.perf_counter() - started
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout
    # The task stepped: a turn left raises the heading by 0.4 rad.
    headings = [float(h) for h in re.findall(r"action [+-]\d\.\d -> pose \[\s*\S+\s+\S+\s+(\S+)\]", out)]
    assert len(headings) == 7 and headings[2] - headings[1] == pytest.approx(0.4, abs=0.02)
    # The agent learned: goals within the 4,000 steps, trials that end at the goal.
    m = re.search(r"4000 steps: (\d+) goals; trial lengths \[([\d, ]*)\]", out)
    assert m and int(m.group(1)) >= 1 and sum(map(int, m.group(2).split(","))) <= 4000
    assert re.search(r"the memory chose (\d+) of the 4000 actions", out)
    assert "frames: (480, 640, 3) (240, 320, 3)" in out
    figure = iio.imread(tmp_path / "trace_and_reward.png")
    frames = iio.imread(tmp_path / "frames.png")
    assert figure.shape[0] > 200 and frames.shape[0] > 200
    # The frame shows the path (the plain path colour, red) on the room.
    red = (frames[..., 0] > 180) & (frames[..., 1] < 80) & (frames[..., 2] < 80)
    assert red.sum() > 500 and np.ptp(frames[..., :3]) > 100
    print(f"tutorial: {seconds:.1f} s")
