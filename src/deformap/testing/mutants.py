"""Seeded mutants of every reader's input, read in a worker process and classified: a test
helper that users' tests may run on their own readers' templates too.

The templates (:mod:`deformap.testing._mutant_templates`) are damaged by the seeded mutators of
:data:`KINDS` (:mod:`deformap.testing._mutators`). Each mutant is read as its reader reads it (a
raw bag as ``deformap map BAG`` does) in a :class:`Worker` process under a per-case time limit,
and counted (:func:`classify`) as:

- ``clean``: refused with a DeformapError (a session: at load, or at least one of its reads);
- ``same``: accepted, and the data read equal the template's;
- ``changed``: accepted with other data, where no check could know (no checksum covers it);
- ``silent``: accepted with other data where a check could have caught it: another number of
  points or pokes, a :data:`STRUCTURAL` mutant accepted, a :data:`REFUSED` mutant (a YAML alias
  bomb) accepted at all, a change a checksum covers, a ``.db3``
  row deleted or repeated (its metadata table counts the messages);
- ``traceback``: any other exception, or an error of several lines; ``hang``: over the time
  limit.
"""

from __future__ import annotations

import functools
import hashlib
import multiprocessing as mp
import shutil
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from deformap.testing._mutant_templates import make_templates
from deformap.testing._mutators import KINDS, kinds_of, mutate_file, mutate_raw, mutate_session

__all__ = ["KINDS", "OUTCOMES", "REFUSED", "STRUCTURAL", "Case", "Worker", "classify",
           "count_table", "read_snapshot", "run_mutants", "table"]

#: How a mutant read is counted (module docstring), in the tables' order.
OUTCOMES = ("clean", "same", "changed", "silent", "traceback", "hang")
#: Mutations that change a file's length or a declared size: accepted as other data, ``silent``.
STRUCTURAL = {"truncate", "count", "extend", "member-truncate", "member-extend", "member-shape",
              "message-truncate", "message-extend", "cut-number"}  # fmt: skip
#: Mutations every reader must refuse: accepted at all, they are ``silent``.
REFUSED = {"alias"}


def _digest(*arrays: Any) -> str:
    h = hashlib.sha256()
    for a in arrays:
        if isinstance(a, tuple):  # a raw bag's robot points: one hull per part
            h.update(_digest(*a).encode())
        else:
            h.update(b"-" if a is None else np.ascontiguousarray(a).tobytes())
    return h.hexdigest()[:16]


def read_snapshot(reader: str, path: str) -> tuple[str, Any]:
    """Read ``path`` as ``reader`` does; ``("ok", snapshot)``, ``("clean", message)`` or
    ``("traceback", message)``. A session's snapshot lists each read (load, observation, pokes)."""
    from deformap.errors import DeformapError

    try:
        if reader in ("config", "scenario"):
            from deformap.run import config_yaml, load_run_config
            from deformap.world import load_scenario

            value = (config_yaml(load_run_config(path)) if reader == "config"
                     else load_scenario(path).to_dict())  # fmt: skip
            return "ok", hashlib.sha256(repr(value).encode()).hexdigest()[:16]
        if not reader.startswith(("session", "raw")):
            from deformap.cloud.io import read_npz, read_pcd, read_ply

            read = {"pcd": read_pcd, "ply": read_ply, "npz": read_npz}[reader.split("-")[0]]
            cloud, extras = read(path)
            return "ok", (len(cloud), _digest(cloud.points, cloud.colors,
                                              *[extras[k] for k in sorted(extras)]))  # fmt: skip
        from deformap.replay import load_raw_bag, load_raw_config, load_session
        from deformap.run import RunConfig

        if reader.startswith("raw"):  # as `deformap map BAG` opens it, settings from beside it
            session = load_raw_bag(path, load_raw_config(Path(path)),
                                   default_force_n=RunConfig().exploration.force_n)
        else:
            session = load_session(path)
        reads: list[Any] = [("obs", _safe(lambda: _digest(session.observation().points)))]
        for i in range(len(session)):
            reads.append((i, _safe(functools.partial(_press_digest, session, i))))
        truth = session.ground_truth
        reads.append(("truth", None if truth is None else _digest(truth.labels, truth.hardness)))
        return "ok", (len(session), tuple(reads))
    except DeformapError as exc:
        if "\n" in str(exc):  # an error is one line (a refused read's too: _safe)
            return "traceback", f"an error of several lines: {str(exc)[:300]!r}"
        return "clean", str(exc)[:300]
    except Exception as exc:  # counting what escapes is the point
        return "traceback", f"{type(exc).__name__}: {str(exc)[:300]}"


def _press_digest(session: Any, index: int) -> str:
    obs = session.press_observation(index)
    record = obs.force_travel
    return _digest(obs.cloud.points, obs.robot_points, obs.contact.tip_center, obs.contact.force,
                   obs.target_xy, np.float64(obs.force_n),
                   None if record is None else record.travel_m,
                   None if record is None else record.force_n)  # fmt: skip


def _safe(read: Callable[[], str]) -> str:
    from deformap.errors import DeformapError

    try:
        return read()
    except DeformapError as exc:
        if "\n" in str(exc):
            raise RuntimeError(f"an error of several lines: {str(exc)[:300]!r}") from None
        return "refused"


def classify(reader: str, kind: str, status: str, got: Any, want: Any) -> str:
    """One of :data:`OUTCOMES` for a mutant read (``want``: the template's snapshot)."""
    if status != "ok":
        return status
    if kind in REFUSED:
        return "silent"
    if got == want:
        return "same"
    if reader in ("config", "scenario"):  # text a user edits: another valid value is theirs
        return "changed"
    if reader.startswith(("session", "raw")):
        n_got, reads = got
        if any(value == "refused" for _, value in reads):
            changed = [k for (k, v), (_, w) in zip(reads, want[1], strict=False)
                       if v not in ("refused", w)]  # fmt: skip
            if not changed and n_got == want[0]:
                return "clean"
        if reader.startswith("raw"):
            return _raw_change(reader, kind)
        # files are covered by the manifest; in session.yaml, text a user may edit, only a lost
        # poke is something a check could see
        return "silent" if kind != "yaml" or n_got < want[0] else "changed"
    # A zip holds a CRC-32 of each member; the member-* mutants forge it to match.
    checksummed = reader == "npz" and not kind.startswith("member-")
    if got[0] != want[0] or kind in STRUCTURAL or checksummed:
        return "silent"
    return "changed"


def _raw_change(reader: str, kind: str) -> str:
    # An MCAP bag's chunks and summary carry CRCs: a byte or record mutant they could have
    # caught. A message rewritten with its CRCs made to match, or the settings YAML, is other
    # valid data unless its length changed. A sqlite3 bag carries no CRC, but its metadata
    # table counts each topic's messages (a row deleted or repeated).
    if kind in STRUCTURAL or (reader == "raw-db3" and kind in ("row-delete", "row-repeat")):
        return "silent"
    if reader == "raw-db3" or kind == "yaml" or kind.startswith("message-"):
        return "changed"
    return "silent"


def _worker(conn: Any) -> None:
    while True:
        job = conn.recv()
        if job is None:
            return
        conn.send(read_snapshot(*job))


@dataclass
class Worker:
    """A reader process; a case over the time limit kills it (a hang) and a new one starts."""

    limit_s: float
    _proc: Any = None
    _conn: Any = None

    def read(self, reader: str, path: Path) -> tuple[str, Any]:
        if self._proc is None:
            ctx = mp.get_context("fork")
            self._conn, child = ctx.Pipe()
            self._proc = ctx.Process(target=_worker, args=(child,), daemon=True)
            self._proc.start()
        self._conn.send((reader, str(path)))
        if self._conn.poll(self.limit_s):
            try:
                reply: tuple[str, Any] = self._conn.recv()
                return reply
            except EOFError:  # the worker died (killed for memory, a crash in C)
                self.close()
                return "traceback", "the reader process died"
        self.close()
        return "hang", f"over {self.limit_s} s"

    def close(self) -> None:
        if self._proc is not None:
            self._proc.kill()
            self._proc.join()
            self._proc = None


@dataclass
class Case:
    """One mutant read: its reader, the kind of mutation, the outcome (:data:`OUTCOMES`) and what
    the read gave."""

    reader: str
    kind: str
    outcome: str
    detail: str


def run_mutants(n_mutants: int, seed: int, limit_s: float, work: Path) -> list[Case]:
    """Make the templates in ``work``, then ``n_mutants`` mutants spread over readers and kinds."""
    templates = make_templates(work / "templates")
    worker = Worker(limit_s)
    want = {r: read_snapshot(r, str(path)) for r, path in templates.items()}
    for r, (status, snap) in want.items():
        if status != "ok":
            raise RuntimeError(f"template {r} does not read: {snap}")
    plan = [(r, k) for r in templates for k in kinds_of(r)]
    cases = []
    try:
        for index in range(n_mutants):
            reader, kind = plan[index % len(plan)]
            rng = np.random.default_rng([seed, index])
            target = work / f"m{index}"
            if reader.startswith("session"):
                mutate_session(templates[reader], target, kind, rng)
            elif reader.startswith("raw"):
                target = mutate_raw(templates[reader], target, kind, rng)
            else:
                target = target.with_suffix(templates[reader].suffix)
                target.write_bytes(mutate_file(templates[reader].read_bytes(), kind, rng))
            status, got = worker.read(reader, target)
            outcome = classify(reader, kind, status, got, want[reader][1])
            cases.append(Case(reader, kind, outcome, str(got)[:300]))
            if reader.startswith("raw"):
                shutil.rmtree(target.parent)
            elif target.is_dir():
                shutil.rmtree(target)
                for link in work.glob(f"{target.name}-outside-*"):
                    link.unlink()
            else:
                target.unlink()
    finally:
        worker.close()
    return cases


def count_table(header: list[str], cases: list[Any], group: str, outcome: str,
                 outcomes: tuple[str, ...], lead: Callable[[list[Any]], list[str]]) -> str:
    """A markdown table: a row per value of the cases' attribute ``group`` (its name, ``lead``'s
    cells, the count of each of ``outcomes`` in their attribute ``outcome``), then the row of all
    (``lead`` of all of them; a "kinds tried" column left empty there)."""
    rows = ["| " + " | ".join(header) + " |",
            "|---|" + "|".join("---" if h == "kinds tried" else "---:" for h in header[1:]) + "|"]
    groups: dict[str, list[Any]] = {}
    for case in cases:
        groups.setdefault(getattr(case, group), []).append(case)
    for name, mine in [*groups.items(), ("**all**", cases)]:
        n = Counter(getattr(c, outcome) for c in mine)
        cells = [name, *lead(mine), *(str(n[o]) for o in outcomes)]
        if name == "**all**" and "kinds tried" in header:
            cells[header.index("kinds tried")] = ""
        rows.append("| " + " | ".join(cells) + " |")
    return "\n".join(rows)


def table(cases: list[Case]) -> str:
    """A markdown table: one row per reader, the kinds tried and the count of each outcome."""
    return count_table(
        ["reader", "kinds tried", "mutants", "clean errors", "accepted, same",
         "accepted, changed (undetectable)", "silently accepted corruptions", "tracebacks",
         "hangs"], cases, "reader", "outcome",
        OUTCOMES, lambda mine: [", ".join(dict.fromkeys(c.kind for c in mine)), str(len(mine))])
