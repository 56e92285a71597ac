"""Map a recorded session: its pokes, in order, through the live loop's mapper; write the result
folder as a live run does (``config.yaml``, ``report.json``, ``map.png``, ``poke-NN.png``).

A poke that cannot be read or processed is skipped and listed in the report; the others count.
``session`` is a session folder (or its ``session.yaml``), or a bag as a robot records it (the
``raw`` layout: a ``.mcap`` / ``.db3`` file or a rosbag2 folder without ``session.yaml``), whose
presses are found in its force stream with the settings of ``replay.RawBagConfig``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from deformap._validation import check_positive
from deformap.errors import InvalidArgumentError
from deformap.replay import (
    RawBagConfig,
    RecordedSession,
    ReplayResult,
    is_raw_bag,
    load_raw_bag,
    load_raw_config,
    load_session,
    map_session,
)
from deformap.run._config import (
    CONFIG_NAME,
    RunConfig,
    config_yaml,
    run_generators,
    session_run_config,
)
from deformap.run._export import write_run_results
from deformap.run._folder import (
    claim_run_folder,
    default_run_folder,
    run_stem,
    write_text,
)
from deformap.run._hooks import NO_HOOKS, RunHooks, RunStart
from deformap.run._report import session_report

__all__ = ["MAP_LAYOUTS", "MapOutput", "map_recorded_session"]

#: What ``map`` reads: ``auto`` tells a raw bag from a session (``replay.is_raw_bag``).
MAP_LAYOUTS = ("auto", "session", "raw")


@dataclass(frozen=True, kw_only=True)
class MapOutput:
    """What :func:`map_recorded_session` wrote and the objects it made.

    Attributes
    ----------
    report : dict
        The content of ``report.json`` (see :mod:`deformap.run._report`).
    session : RecordedSession
    replay : ReplayResult
    config : RunConfig
        The configuration the session was mapped with.
    folder : Path
    """

    report: dict[str, Any]
    session: RecordedSession
    replay: ReplayResult
    config: RunConfig
    folder: Path


def map_recorded_session(
    session: Path,
    out: Path | None = None,
    *,
    config: RunConfig | None = None,
    seed: int | None = None,
    figures: bool = True,
    hooks: RunHooks = NO_HOOKS,
    layout: Literal["auto", "session", "raw"] = "auto",
    raw_config: Path | None = None,
    raw_settings: dict[str, Any] | None = None,
    variance_max: float | None = None,
    rerun: bool = False,
) -> MapOutput:
    """Map the session at ``session`` (its folder or its ``session.yaml``) into ``out``.

    Parameters
    ----------
    session : Path
    out : Path, optional
        A new or empty folder (default: :func:`~deformap.run.default_run_folder` of the
        session's folder name, kind ``map``).
    config : RunConfig, optional
        Default: the configuration the session was recorded with, else the defaults (see
        :func:`~deformap.run.session_run_config`).
    seed : int, optional
        Seed of the surface fit; default: the session's, so a recorded simulation maps to the βs
        of its live run.
    figures : bool
        Write ``map.png`` and the ``poke-NN.png``.
    hooks : RunHooks
    layout : {"auto", "session", "raw"}
        ``raw`` reads ``session`` as a bag a robot recorded; ``auto`` decides by its form.
    raw_config : Path, optional
        The raw recording's settings YAML (default: the one beside the bag, see
        ``replay.raw_config_file``, if it exists).
    raw_settings : dict, optional
        ``replay.RawBagConfig`` settings that win over the file's (command-line options).
    variance_max : float, optional
        Top of ``map.png``'s variance colour scale (default: the map's own largest variance).
    rerun : bool
        Also write ``run.rrd``, the run as a rerun recording (extra ``rerun``).

    Raises
    ------
    ConfigError, FileFormatError
        The session cannot be loaded, its recorded configuration is malformed, or ``out`` is not
        empty, not creatable or held by another run (before any poke is mapped).
    FileWriteError
        A file of the result could not be written (a full disk, a read-only file system, ...).
    """
    if variance_max is not None:  # before any work
        check_positive("variance_max", variance_max)
    recorded = _open(session, config, layout, raw_config, raw_settings or {})
    cfg = session_run_config(recorded, config, seed)
    stem = recorded.path.name or "session"
    folder = out or default_run_folder(run_stem(stem), "map", cfg.seed)
    with claim_run_folder(folder, what="result"):
        title = f"{recorded.path} ({len(recorded)} pokes, {recorded.form} form)"
        hooks.start(RunStart(kind="map", title=title, folder=folder, total=len(recorded)))
        _, explore_rng = run_generators(cfg.seed)
        hooks.stage("mapping")
        replay = map_session(recorded, cfg.exploration, rng=explore_rng,
                             on_poke=lambda poke: hooks.poke(poke.record))  # fmt: skip
        write_text(folder / CONFIG_NAME, config_yaml(cfg))
        report = session_report(cfg, recorded, replay)
        write_run_results(folder, replay.result, report, figures=figures,
                          truth=recorded.ground_truth,
                          title=f"{stem}: {len(replay.result.pokes)} pokes", hooks=hooks,
                          variance_max=variance_max)  # fmt: skip
        if rerun:
            from deformap.run._figures import write_rerun

            write_rerun(folder / "run.rrd", replay.result)
    return MapOutput(report=report, session=recorded, replay=replay, config=cfg, folder=folder)


def _open(path: Path, config: RunConfig | None, layout: str, raw_config: Path | None,
          raw_settings: dict[str, Any]) -> RecordedSession:  # fmt: skip
    if layout not in MAP_LAYOUTS:
        raise InvalidArgumentError(f"`layout` must be one of {list(MAP_LAYOUTS)}; got {layout!r}")
    given = {k: v for k, v in raw_settings.items() if v is not None}
    if given:  # each value checked itself first, whatever the recording turns out to be
        RawBagConfig(**given)
    raw = layout == "raw" or (layout == "auto" and is_raw_bag(path))
    if not raw:
        tolerance = raw_settings.get("stamp_tolerance_s")  # every layout takes it
        if raw_config is not None or any(v is not None for k, v in raw_settings.items()
                                         if k != "stamp_tolerance_s"):
            raise InvalidArgumentError(
                f"raw recording settings apply to a bag as a robot records it; {str(path)!r} is "
                "read as a deformap session (pass --layout raw to read it as a raw bag)")
        return load_session(path, stamp_tolerance_s=tolerance)
    settings = load_raw_config(path, raw_config, **raw_settings)
    force = (config or RunConfig()).exploration.force_n
    return load_raw_bag(path, settings, default_force_n=force)
