"""Help that says what a command takes (issue 59, item 2): every command with --robot lists
the registered robots, the shipped mounts, a mount .toml file and a robot .xml file;
every command with --condition lists its values. Read from the commands' own parsers
(every command, so a new one is held to it) and, for check, run and render, from `ebrl
CMD --help` as a user types it."""
import argparse
import re

import pytest

from experiments import cli
from experiments.commands import arguments
from ebrl.config import CONDITIONS
from helpers import ebrl, ebrl_here
from tasks.robots import MOUNTS, ROBOTS


def _options():
    """{command: {option: its argparse Action}} of every `ebrl` command."""
    parser = cli.build_parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return {name: {s: a for a in sub._actions for s in a.option_strings}
            for name, sub in commands.choices.items()}


def _flat(text):
    """Help text with argparse's line breaks and indents made single spaces."""
    return re.sub(r"\s+", " ", text)


def _says_what_robot_takes(text, xml=True):
    text = _flat(text)
    assert "a mount file (.toml" in text, text
    assert ("a robot file of the naming contract (.xml, with --drive)" in text) == xml, text
    for name in (*ROBOTS, *MOUNTS):
        assert name in text, (name, text)


def test_every_robot_option_lists_what_it_takes():
    """Every command's --robot, but fit's (the paper's two robots by drive, listed); a .xml
    file is offered where the command has --drive."""
    options = _options()
    with_robot = [c for c, o in options.items() if "--robot" in o]
    assert {"check", "run", "render", "sweep", "ablate", "evolve", "bench"} <= set(with_robot)
    for command in with_robot:
        text = options[command]["--robot"].help
        if command == "fit":
            assert "two_wheel or floating" in text
            continue
        _says_what_robot_takes(text, xml="--drive" in options[command])


def test_every_condition_option_lists_its_values():
    options = _options()
    with_condition = [c for c, o in options.items() if "--condition" in o]
    assert {"run", "render", "sweep"} <= set(with_condition)
    for command in with_condition:
        action = options[command]["--condition"]
        help_text = _flat(action.help)
        for value in CONDITIONS:
            assert f"{value}: the intrinsic behaviour" in help_text, (command, help_text)
        assert action.metavar.startswith("{random,avoidance"), action.metavar


@pytest.mark.parametrize("command", ["check", "run", "render"])
def test_help_on_the_command_line_says_what_robot_and_condition_take(command):
    proc = ebrl_here(command, "--help")
    assert proc.returncode == 0 and proc.stderr == "", proc
    _says_what_robot_takes(proc.stdout.split("--robot NAME", 2)[2])
    if command != "check":
        assert "--condition {random,avoidance" in proc.stdout
        assert "avoidance: the intrinsic behaviour Section 3.4's obstacle avoidance" in \
            _flat(proc.stdout)


def test_a_mount_file_is_what_the_help_says_robot_takes(tmp_path):
    """The help's word holds: a .toml path is taken by --robot (a missing one is named as
    a missing mount file, not an unknown robot)."""
    proc = ebrl_here("check", "--robot", tmp_path / "none.toml", "--actions", "1")
    assert proc.returncode == 2
    assert proc.stderr.strip() == f"ebrl: error: no mount file at {tmp_path / 'none.toml'}"
    assert arguments.robot_list("x.toml") == ("x.toml",)


@pytest.mark.slow
def test_run_help_in_a_process_of_its_own():
    proc = ebrl("run", "--help")
    assert proc.returncode == 0, proc.stderr
    _says_what_robot_takes(proc.stdout.split("--robot NAME", 2)[2])
    assert "all: both; default: all" in _flat(proc.stdout)
