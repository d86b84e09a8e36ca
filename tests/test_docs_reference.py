"""The reference pages generated from the package (tools/docs_reference.py) are the ones in
docs/: none is stale, and each lists everything its source defines: every sub-command and
option of the parser, every field of the robot file and every sensor channel, every slot of
a compiled controller's readings, every column a run writes. Their tables stay tables
whatever characters the help texts hold."""

import argparse
import importlib.util
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def tool():
    spec = importlib.util.spec_from_file_location(
        "docs_reference", ROOT / "tools" / "docs_reference.py"
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def pages(tool):
    return {str(path): text for path, text in tool.generated_pages().items()}


def section(text: str, heading: str) -> str:
    """The text under ``heading`` up to the next heading of its level or above."""
    start = text.index(heading + "\n")
    level = heading.split(" ")[0]
    rest = text[start + len(heading) + 1 :]
    ends = [m.start() for m in re.finditer(rf"^#{{1,{len(level)}}} ", rest, flags=re.M)]
    return rest[: ends[0]] if ends else rest


def test_no_generated_page_is_stale(tool, pages):
    """The committed pages are what the package generates now (the site's build refuses
    otherwise): python tools/docs_reference.py write after changing the package."""
    assert tool.stale_pages() == []
    assert tool.main(["check"]) == 0


def test_generation_is_deterministic(tool, pages):
    again = {str(path): text for path, text in tool.generated_pages().items()}
    assert again == pages
    for text in pages.values():
        assert not re.search(r"0x[0-9a-f]{6,}", text), "a memory address"
        assert str(ROOT) not in text, "an absolute path"


def test_every_subcommand_and_option_is_in_the_cli_reference(pages):
    from scoutsim.cli import build_parser

    cli = pages["reference/cli.md"]
    parser = build_parser()
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    assert sub.choices, "the parser has sub-commands"
    for name, command in sub.choices.items():
        text = section(cli, f"## scoutsim {name}")
        assert f"usage: scoutsim {name}" in text
        for action in command._actions:
            for flag in action.option_strings:
                if flag not in ("-h", "--help"):
                    assert f"`{flag}" in text or f", {flag}" in text, (name, flag)


def test_the_cli_reference_has_the_exit_codes_and_what_the_readme_promised(pages):
    cli = pages["reference/cli.md"]
    exit_codes = section(cli, "## Exit codes")
    for code in ("0 success", "1 numerical failure", "2 bad usage", "74 ", "130 interrupted"):
        assert code in exit_codes
    run = section(cli, "## scoutsim run")
    for fact in ("--stream", "--keep", "`--format`", "--max-hours", "gzip-compressed"):
        assert fact in run


def test_every_field_and_sensor_channel_is_in_the_robot_file_reference(pages):
    from scoutsim.control.sensors import CHANNELS
    from scoutsim.parameters.schema import PER_LEG_FIELDS, field_schema

    page = pages["reference/robot-file.md"]
    for name, spec in field_schema().items():
        text = section(page, f"## [{spec.section}]")
        rows = [line for line in text.splitlines() if line.startswith(f"| `{name}` |")]
        assert len(rows) == 1, name
        assert rows[0].endswith("| (back, front) |") == (name in PER_LEG_FIELDS), name
    sensors = section(page, "## [sensors]")
    for channel in CHANNELS:
        assert f"| `{channel}` |" in sensors
    assert 'unit = "g" }' in page


def test_every_slot_of_the_readings_is_listed_once(pages):
    from scoutsim.control.sensors import N_SENSORS

    rows = [
        line for line in pages["reference/sensor-slots.md"].splitlines() if re.match(r"\| \d", line)
    ]
    assert [int(line.split("|")[1]) for line in rows] == list(range(N_SENSORS))


def test_every_column_a_run_writes_is_in_the_output_files_reference(tool, pages):
    page = pages["reference/output-files.md"]
    for table_name, (columns, _) in tool._empty_result().tables().items():
        text = section(page, f"## {table_name}")
        for name in columns:
            if table_name == "events" and re.search(r"(?<!^energy)_(before|after)$", name):
                pattern = re.sub(r"^\w+_(before|after)$", r"{state}_\1", name)
            else:
                pattern = re.sub(r"_(back|front)$", "_{leg}", name)
                if pattern.startswith("cumulative_energy_") and pattern.endswith("_{leg}"):
                    pattern = "cumulative_energy_{flow}_{leg}"
            assert f"| `{pattern}` |" in text, (table_name, name)
    manifest = section(page, "## manifest.json")
    for status in ("complete", "partial", "writing"):
        assert f"| `{status}` |" in manifest


def test_tables_keep_their_cells_whatever_the_text(tool, pages):
    """A cell's text with Markdown's table border or markup in it is escaped: every row
    of a table has as many cells as its header."""
    assert tool.md_escape("a | b * c <d>") == "a \\| b \\* c &lt;d&gt;"
    for path, text in pages.items():
        lines = text.splitlines()
        for i, line in enumerate(lines):
            if line.startswith("|---"):
                width = len(re.split(r"(?<!\\)\|", lines[i - 1]))
                j = i + 1
                while j < len(lines) and lines[j].startswith("|"):
                    assert len(re.split(r"(?<!\\)\|", lines[j])) == width, (path, lines[j])
                    j += 1


def test_the_robot_file_examples_load(pages, tmp_path):
    """The page's TOML examples are robot files the loaders accept, with the units they
    show converted to SI."""
    import math

    import scoutsim

    blocks = re.findall(r"```toml\n(.*?)```", pages["reference/robot-file.md"], flags=re.S)
    assert len(blocks) == 2
    path = tmp_path / "robot.toml"
    path.write_text("\n".join(blocks))
    robot, controller = scoutsim.load_parameters(path)
    assert robot.leg_mass == pytest.approx(0.97)  # written as 970 g
    assert robot.per_leg("leg_stiffness") == pytest.approx((3520.0, 3000.0))  # N/mm
    assert controller.touchdown_angle_front == pytest.approx(0.3665)
    sensors = scoutsim.load_sensors(path, robot)
    assert sensors.pitch.noise == pytest.approx(math.radians(0.3))
    assert sensors.seed == 7
