"""The table of orbit sensitivities of docs/explanation/orbit-sensitivities.md: every
parameter's elasticity of the default Model II orbit's metrics (Table I, default floor).

    python tools/sensitivity_table.py > table.md

Runs ``scoutsim orbit --duration 8 --sensitivity all --json`` (about half a minute after
the first compile) and prints the Markdown table, the parameters that move the speed most
first; a parameter at 0 (no elasticity) shows its derivatives, ``d = ...`` (SI per SI).
"""

from __future__ import annotations

import contextlib
import io
import json
import math

from scoutsim.cli import main

COLUMNS = (
    ("mean_speed_m_s", "speed"),
    ("duty_factor_front", "front duty factor"),
    ("electrical_power_w", "electrical power"),
    ("cost_of_transport", "cost of transport"),
    ("spectral_radius", "spectral radius"),
)


def sensitivities() -> dict:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(["orbit", "--duration", "8", "--sensitivity", "all", "--json", "--no-progress"])
    if code != 0:
        raise SystemExit(f"scoutsim orbit exited {code}")
    return json.loads(out.getvalue())


def table(d: dict) -> str:
    rows = [(n, s) for n, s in d["sensitivities"].items() if s["status"] == "ok"]

    def size(row) -> float:
        e = row[1]["elasticity"]["mean_speed_m_s"]
        return -1.0 if e is None or math.isnan(e) else abs(e)

    rows.sort(key=size, reverse=True)
    head = "| parameter | value (SI) | " + " | ".join(label for _, label in COLUMNS) + " |"
    lines = [head, "|---|---:|" + "---:|" * len(COLUMNS)]
    for name, s in rows:
        cells = []
        for key, _ in COLUMNS:
            e = s["elasticity"][key]
            if e is None or math.isnan(e):  # a parameter at 0: its derivative (SI per SI)
                cells.append(f"d = {s['derivative'][key]:+.3g}")
            else:
                cells.append(f"{e:+.3f}")
        lines.append(f"| `{name}` | {s['value']:.6g} | " + " | ".join(cells) + " |")
    for name, s in d["sensitivities"].items():
        if s["status"] != "ok":
            lines.append(f"| `{name}` | {s['value']:.6g} | {s['status']} |" + " |" * 4)
    return "\n".join(lines)


if __name__ == "__main__":
    print(table(sensitivities()))
