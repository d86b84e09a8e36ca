"""The options a command line gave, told from their defaults: a command refuses an option
its chosen mode would ignore (``orbit --passive --model I``) instead of dropping it."""

from __future__ import annotations

import argparse

from ._common import UsageError


def _without_defaults(parser: argparse.ArgumentParser) -> None:
    """Every option of ``parser`` and its sub-commands' parsers left unset unless given."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                _without_defaults(sub)
        elif action.dest != "help":
            action.default = argparse.SUPPRESS


def given_options(parser: argparse.ArgumentParser, argv: list[str]) -> frozenset[str]:
    """The destinations of the options typed in ``argv`` (a command line ``parser``
    accepts; the parser is changed: pass a fresh one), however spelled (``--fric 0.8``,
    ``--friction=0.8``): a second parse with no defaults."""
    _without_defaults(parser)
    return frozenset(vars(parser.parse_args(argv)))


def refuse_given(args, dests: tuple[str, ...], why: str) -> None:
    """A UsageError naming the first of the options ``dests`` (argparse destinations) the
    command line gave, with ``why`` (e.g. "with --passive"): options a mode would ignore
    are refused, not dropped. ``args.given``: the options typed (``cli.given_options``;
    none when a command is called with a namespace of its own)."""
    given = getattr(args, "given", ())
    for dest in dests:
        if dest in given:
            raise UsageError(f"--{dest.replace('_', '-')} is not allowed {why}")
