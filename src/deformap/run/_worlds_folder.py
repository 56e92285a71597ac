"""The folder of a worlds benchmark: its ``bench.json``, one file per world, and the summary files.

The folder holds ``bench.json`` (the settings, written first, with :data:`BENCH_FORMAT`),
``worlds/world-NNNNN.json`` (one :class:`~deformap.eval.WorldResult` per world, every appearance
arm of it, written atomically as it arrives: a killed run loses at most the worlds in flight)
and, rewritten after every world, ``runs.csv``, ``summary.json``, ``summary.md`` and
``curves.png``. A folder of another format is
refused in one line naming both versions: its worlds would be read with a meaning they lack.
"""

from __future__ import annotations

import contextlib
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from deformap import __version__
from deformap.errors import ConfigError, DeformapError
from deformap.eval import (
    WorldResult,
    accuracy_curves,
    markdown_summary,
    runs_csv,
    summarise_worlds,
)
from deformap.run._folder import to_json, write_text
from deformap.run._worlds_config import WorldsBenchConfig, exploration_with
from deformap.viz import plot_world_curves

__all__ = ["BENCH_FORMAT", "SETTINGS_NAME", "finished_worlds", "read_bench", "read_world",
           "start_folder", "world_path", "write_bench", "write_summary"]

SETTINGS_NAME = "bench.json"
#: Version of a benchmark folder: 3 maps each world under appearance arms (``appearances`` in
#: the settings; world files of ``pokes_format`` 4); 2 recorded the exploration as the settings
#: that differ from the defaults (``exploration``: dotted key → value), its worlds unpainted;
#: 1 (no ``format`` key) had one key per switch.
BENCH_FORMAT = 3


def world_path(folder: Path, index: int) -> Path:
    return folder / "worlds" / f"world-{index:05d}.json"


def write_bench(folder: Path, config: WorldsBenchConfig, **extra: Any) -> Path:
    """Write ``bench.json``: the version, :data:`BENCH_FORMAT`, the result settings and
    ``extra``."""
    return write_text(folder / SETTINGS_NAME,
                      to_json({"deformap": __version__, "format": BENCH_FORMAT,
                               "settings": config.result_settings(), **extra}))


def _stored_settings(folder: Path, what: str) -> dict[str, Any]:
    """The ``settings`` of ``folder``'s ``bench.json``, refused unless of :data:`BENCH_FORMAT`."""
    path = folder / SETTINGS_NAME
    try:
        stored = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise ConfigError(f"{what}: {path} cannot be read: {exc}".splitlines()[0]) from None
    version = stored.get("format", 1) if isinstance(stored, dict) else None
    if version != BENCH_FORMAT:
        raise ConfigError(f"{what}: {path} is a worlds benchmark of format {version!r}; this "
                          f"version of deformap reads format {BENCH_FORMAT} only")
    settings = stored.get("settings")
    if not isinstance(settings, dict):
        raise ConfigError(f"{what}: {path} holds no `settings` object")
    return settings


def read_bench(folder: Path, *, what: str = "source") -> WorldsBenchConfig:
    """The benchmark whose ``bench.json`` is in ``folder`` (``worlds`` 1: count the files).

    Raises
    ------
    ConfigError
        No ``bench.json`` of :data:`BENCH_FORMAT`, or settings this version refuses.
    """
    settings = dict(_stored_settings(Path(folder), what))
    try:
        exploration = exploration_with(settings.pop("exploration", {}))
        given: dict[str, Any] = {k: tuple(v) if isinstance(v, list) else v
                                 for k, v in settings.items()}
        return WorldsBenchConfig(worlds=1, exploration=exploration, **given)
    except (DeformapError, TypeError) as exc:
        raise ConfigError(f"{what}: {Path(folder) / SETTINGS_NAME}: {exc}".splitlines()[0]
                          ) from None


def start_folder(config: WorldsBenchConfig, folder: Path) -> None:
    """Start the benchmark ``config`` in ``folder`` (created and locked by the caller,
    :func:`~deformap.run._folder.claim_run_folder`), or check that it holds the same benchmark to
    resume.

    Raises
    ------
    ConfigError
        ``folder`` holds something else, another format, or a benchmark with other settings.
    """
    if (folder / SETTINGS_NAME).is_file():
        theirs = _stored_settings(folder, "--out")
        ours = json.loads(to_json(config.result_settings()))
        if theirs != ours:
            differ = ", ".join(f"{k}: {theirs.get(k)!r} there, {ours.get(k)!r} here"
                               for k in sorted(set(ours) | set(theirs))
                               if theirs.get(k) != ours.get(k))
            raise ConfigError(
                f"--out {str(folder)!r} holds a worlds benchmark with other settings "
                f"({differ}); choose another --out or the same settings")
    else:
        write_bench(folder, config)
    (folder / "worlds").mkdir(exist_ok=True)


def read_world(path: Path, what: str = "source") -> WorldResult:
    """The world stored in ``path``; one :class:`ConfigError` line naming it if it is not one."""
    try:
        return WorldResult.from_dict(json.loads(path.read_text(encoding="utf-8")))
    except (OSError, ValueError) as exc:  # unreadable, not JSON, or refused
        raise ConfigError(f"{what}: {path} is not a stored world: {exc}".splitlines()[0]
                          ) from None


def finished_worlds(folder: Path, worlds: int) -> dict[int, WorldResult]:
    """The worlds below ``worlds`` that finished in ``folder`` (any other is computed again)."""
    done: dict[int, WorldResult] = {}
    for index in range(worlds):
        path = world_path(folder, index)
        if path.is_file():
            with contextlib.suppress(ConfigError):
                result = read_world(path)
                if result.status == "ok":
                    done[index] = result
    return done


def write_summary(folder: Path, config: WorldsBenchConfig, results: Sequence[WorldResult]
                  ) -> tuple[dict[str, Any], list[Path]]:
    """Write ``runs.csv``, ``summary.json``, ``summary.md`` and ``curves.png`` of ``results``;
    return the summary and the files. The figure's panels are the layout families, or, where a
    family was mapped blind beside the prior, the appearance families with both."""
    combos, arms, k = config.combinations(), config.arms(), config.max_pokes
    summary = summarise_worlds(results, combos, k, arms=arms)
    summary["settings"] = {**config.result_settings(), "worlds": config.worlds}
    files = [write_text(folder / "runs.csv", runs_csv(results, combos, arms)),
             write_text(folder / "summary.json", to_json(summary)),
             write_text(folder / "summary.md", markdown_summary(summary))]
    paired = any(prior == "off" for _, prior in arms)
    by = "appearance" if paired else "layout"
    curves = accuracy_curves(results, combos, k, arms=arms, by=by)
    if curves:
        blind = accuracy_curves(results, combos, k, arms=arms, by=by, prior="off")
        plot_world_curves(curves, good_accuracy=summary["good_accuracy"],
                          path=folder / "curves.png", blind=blind if paired else None)
        files.append(folder / "curves.png")
    return summary, files
