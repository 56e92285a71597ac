"""The README's Python example runs as written, from ``deformap`` itself (not deformap.testing)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import deformap

README = Path(__file__).resolve().parents[1] / "README.md"


def _example() -> str:
    text = README.read_text(encoding="utf-8")
    after = text.split("In Python:", 1)[1]
    match = re.search(r"```python\n(.*?)```", after, flags=re.S)
    assert match is not None
    return match.group(1)


def test_the_readme_example_imports_nothing_from_the_test_helpers() -> None:
    assert "deformap.testing" not in _example()


def test_the_readme_example_runs() -> None:
    code = _example() + (
        "\nassert beta_mean.shape == beta_var.shape == (80, 120)"
        "\nassert len(result.pokes) == 4 and regions is not None"
        "\nprint('ok')\n"
    )
    src = str(Path(deformap.__file__).resolve().parents[1])
    done = subprocess.run([sys.executable, "-c", f"import sys; sys.path.insert(0, {src!r})\n" + code],
                          capture_output=True, text=True, timeout=300)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().endswith("ok")


def test_import_deformap_is_cheap_and_its_names_load_on_first_use() -> None:
    src = str(Path(deformap.__file__).resolve().parents[1])
    code = (f"import sys; sys.path.insert(0, {src!r}); import deformap; "
            "heavy = [m for m in ('numpy', 'scipy', 'matplotlib', 'deformap.world', "
            "'deformap.explore', 'deformap.gp') if m in sys.modules]; "
            "assert heavy == [], heavy; "
            "assert deformap.GaussianRandomField.__module__ == 'deformap.gp._field'; "
            "assert callable(deformap.explore.explore); "
            "import deformap.explore as e; assert e.__name__ == 'deformap.explore'; "
            "missing = [n for n in deformap.__all__ if getattr(deformap, n, None) is None]; "
            "assert missing == [], missing; print('ok')")  # fmt: skip
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "ok"
