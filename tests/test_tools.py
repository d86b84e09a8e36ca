"""The developer tools stay in step with the code they read: every mutant of the mutation
study (tools/mutation_study.py) finds the exact source text it changes, once, and names
test files that exist (a move or a reformat of the code would otherwise leave a mutant
that silently changes nothing)."""

import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _mutation_study():
    spec = importlib.util.spec_from_file_location(
        "mutation_study", ROOT / "tools" / "mutation_study.py"
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules["mutation_study"] = module  # its dataclasses look their module up
    try:
        spec.loader.exec_module(module)
    finally:
        sys.modules.pop("mutation_study", None)
    return module


def test_every_mutant_finds_its_source_text_once_and_its_tests_exist():
    study = _mutation_study()
    assert study.MUTANTS
    wrong = []
    for m in study.MUTANTS:
        n = (ROOT / m.file).read_text().count(m.old)
        if n != 1:
            wrong.append(f"{m.name}: {m.file} holds its text {n} times")
        for aimed in m.aimed:
            path = aimed.split("::")[0]
            if not (ROOT / path).exists():
                wrong.append(f"{m.name}: {path} does not exist")
    missing = [p for p in study.TEST_FILES if not (ROOT / p).exists()]
    assert not wrong and not missing, wrong + missing
