"""The benchmark modules whose machinery the robustness tests run: ``benchmarks/robustness.py``
(reader mutants, their classification) and ``benchmarks/_cli_mutants.py`` (command-line
mutants), loaded from their files (``benchmarks/`` is no package)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import pytest

_BENCHMARKS = Path(__file__).resolve().parents[2] / "benchmarks"


def _load(file: str, name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(name, _BENCHMARKS / file)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="session")
def bench() -> ModuleType:
    return _load("robustness.py", "deformap_bench_robustness")


@pytest.fixture(scope="session")
def cm() -> ModuleType:
    return _load("_cli_mutants.py", "deformap_bench_cli_mutants")
