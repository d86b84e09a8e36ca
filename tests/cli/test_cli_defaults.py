"""Every sub-command's parsed defaults are what its ``--help`` says (scoutsim.cli).

A default given by a shared parent parser can leak from one command into another (an
argparse ``set_defaults`` changes the shared action); this test reads each command's help
text and its parsed namespace independently and compares them, so a help that says
"default: 10" while the command runs 20 fails here.
"""

import argparse
import math
import re

import pytest

from scoutsim.cli import COMMANDS, build_parser

#: "(default: X)" or "default: X;" / "default: X," in a help string
_DEFAULT = re.compile(r"\(default:\s*([^();]*?)\)|default:\s*([^();,]*?)[;,]")

#: positional arguments a command needs before it parses (a placeholder file name)
_POSITIONALS = {
    "plot": ["x"],
    "animate": ["x", "--out", "a.gif"],
    "rig": ["free-swing"],
    "continue": ["--vary", "robot.belt_stiffness=400:600", "--out", "d"],
}


def _subparsers():
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return parser, sub.choices


def _help_default(action):
    """The default an option's help text states (a string), or None if it states none."""
    if not action.help or action.help is argparse.SUPPRESS:
        return None
    text = (
        action.help % {"default": action.default, "prog": ""}
        if "%(" in action.help
        else action.help
    )
    m = _DEFAULT.search(text)
    if m is None:
        return None
    return (m.group(1) if m.group(1) is not None else m.group(2)).strip()


def _number(text):
    try:
        return float(text)
    except ValueError:
        return None


def _agrees(stated: str, value, action) -> bool:
    """Whether the help's stated default ``stated`` describes the parsed ``value``."""
    if isinstance(action, argparse.BooleanOptionalAction):
        return stated == (
            "--" + action.dest.replace("_", "-")
            if value
            else "--no-" + action.dest.replace("_", "-")
        )
    if isinstance(value, bool):
        return stated.lower() in (str(value).lower(), "on" if value else "off")
    if isinstance(value, (int, float)):
        first = stated.split()[0]
        n = _number(first)
        if n is None:
            return False
        return n == value or (math.isinf(n) and math.isinf(value))
    if isinstance(value, (list, tuple)):
        items = [s.strip() for s in stated.split(",")]
        if len(items) != len(value):
            return False
        return all(
            (_number(s) == v) if isinstance(v, (int, float)) else s == str(v)
            for s, v in zip(items, value)
        )
    if isinstance(value, str):
        return stated.split()[0] == value
    return False


def _cases():
    _, subs = _subparsers()
    for name, sub in subs.items():
        for action in sub._actions:
            if action.dest in ("help",) or not action.option_strings:
                continue
            stated = _help_default(action)
            if stated is None:
                continue
            yield pytest.param(name, action.dest, stated, id=f"{name}-{action.dest}")


def test_every_command_is_covered():
    """Each registered command has a parser here (a new command is checked too)."""
    _, subs = _subparsers()
    assert {c.NAME for c in COMMANDS} == set(subs)


@pytest.mark.parametrize("command,dest,stated", list(_cases()))
def test_parsed_default_is_what_the_help_says(command, dest, stated):
    """The value the command runs with when the option is not given is the one its help
    states (values are compared as numbers, lists of numbers or words)."""
    parser, subs = _subparsers()
    ns = parser.parse_args([command] + _POSITIONALS.get(command, []))
    value = getattr(ns, dest)
    action = next(a for a in subs[command]._actions if a.dest == dest)
    if value is None:
        # unset: the command works the value out when it runs (the model's own start, the
        # number of cores, ...); the help then says what it will be, which is a rule, not
        # a parsed value, so there is nothing to compare here
        return
    assert _agrees(stated, value, action), (
        f"scoutsim {command} --help says the default of {dest} is {stated!r}, the parser "
        f"gives {value!r}"
    )


@pytest.mark.parametrize(
    "command,expected", [("run", 10.0), ("basin", 10.0), ("sweep", 10.0), ("tune", 20.0)]
)
def test_duration_defaults_are_their_own(command, expected):
    """Each simulating command's --duration is its own (run, basin and sweep 10 s as the
    command-line reference says, tune 20 s): none leaks into another through the shared options."""
    parser, _ = _subparsers()
    assert parser.parse_args([command]).duration == expected


def test_durations_come_from_the_library_defaults():
    """One home for each default: the command line's durations are the functions'."""
    import inspect

    from scoutsim import simulate
    from scoutsim.analysis.basin import basin_of_attraction
    from scoutsim.analysis.sweep import SweepBase
    from scoutsim.analysis.tune import TuneRuns

    parser, _ = _subparsers()
    assert (
        parser.parse_args(["run"]).duration
        == inspect.signature(simulate).parameters["duration"].default
    )
    assert (
        parser.parse_args(["basin"]).duration
        == inspect.signature(basin_of_attraction).parameters["duration"].default
    )
    assert parser.parse_args(["sweep"]).duration == SweepBase.duration
    assert parser.parse_args(["tune"]).duration == TuneRuns.duration
