"""What a place whose modulus cannot be read should do to a run: β for good, or be avoided (issue 16).

    OMP_NUM_THREADS=1 PYTHONPATH=src python benchmarks/unread_place.py RUN [--workers 2] [--out F]

``RUN`` is a folder written by ``deformap bench worlds`` with the modulus field among its fields
and ``--unread-place beta`` (the default before ``avoid``): a run that presses a place twice
without a usable force–travel record maps on the β-field from then on. This maps every world of
``RUN`` where a combination did so again, with the same settings and ``unread_place: avoid``
(the run keeps the modulus field and leaves that place out of its targets and its stopping
rule). The baseline is ``RUN``'s own rows of those worlds: a world's presses are a function of
its seed and the settings, so every press before the fallback is the same, and every press of
the combinations that never fell back (the script checks it on the stored pokes, places and
readings to 1e-9, and says so where they differ: then the worlds are not paired).

It prints, for each combination that fell back (``world``, ``strategy``) and over them, the
pokes to region accuracy 0.9 (``max_pokes + 1`` when never), the accuracy and the modulus error
after the last poke under each rule, and the medians of the whole run with those worlds mapped
under ``avoid``. ``--out`` writes the new worlds' results as JSON; ``--again FILE`` reads such
a file instead of mapping again (the tables only).
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path
from typing import Any

for _name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")  # the workers are spawned: they read these as numpy loads

import numpy as np  # noqa: E402
from numpy.typing import NDArray  # noqa: E402

from deformap.eval import GOOD_ACCURACY as GOOD  # noqa: E402
from deformap.eval import pokes_to_good, run_world, summarise_worlds  # noqa: E402
from deformap.run._worlds import SETTINGS_BEFORE, worker_pool  # noqa: E402


def _given_up(result: dict[str, Any]) -> set[tuple[str, str]]:
    """Combinations whose map field was β at their last poke although they asked for the modulus:
    gone to β for good (a run that read no modulus at all is among them, which ``avoid`` does
    not change)."""
    last: dict[tuple[str, str], dict[str, Any]] = {}
    for row in result["rows"]:
        key = (row["strategy"], row["field"])
        if key not in last or row["poke"] >= last[key]["poke"]:
            last[key] = row
    return {k for k, r in last.items() if r["field"] == "modulus" and r["map_field"] == "beta"}


def _curve(rows: list[dict[str, Any]], strategy: str, cut: str) -> list[dict[str, Any]]:
    return sorted((r for r in rows if r["strategy"] == strategy and r["field"] == "modulus"
                   and r["cut"] == cut), key=lambda r: r["poke"])


def _same_pokes(a: dict[str, list[Any]], b: dict[str, list[Any]], until: int) -> bool:
    """The stored pokes numbered below ``until`` (from 1) at the same places with the same values,
    to 1e-9 relative: the same presses (a score may still differ in its last bits, or a τ of one
    poke be 1.0 or undefined, as the BLAS sums in another order)."""
    def kept(d: dict[str, list[Any]]) -> NDArray[np.float64]:
        keep = np.asarray(d["index"]) < until - 1
        return np.column_stack([np.asarray(d[c], float)[keep] for c in ("x", "y", "value")])

    x, y = kept(a), kept(b)
    return x.shape == y.shape and bool(np.allclose(x, y, rtol=1e-9, atol=1e-12))


def _fell(curve: list[dict[str, Any]]) -> int:
    """The poke from which every later row of ``curve`` mapped on β."""
    return next(r["poke"] for r in curve if r["map_field"] == "beta"
                and all(q["map_field"] == "beta" for q in curve if q["poke"] >= r["poke"]))




def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("run", type=Path, help="a bench worlds folder mapped on the modulus field")
    parser.add_argument("--workers", type=int, default=2, help="local processes (default 2)")
    parser.add_argument("--out", type=Path, help="a JSON file for the worlds mapped again")
    parser.add_argument("--again", type=Path, help="a JSON file --out wrote: no mapping")
    args = parser.parse_args()
    if args.workers < 1:
        raise SystemExit(f"--workers: expected an integer >= 1; got {args.workers}")
    try:
        settings = {**SETTINGS_BEFORE, **json.loads((args.run / "bench.json").read_text(
            encoding="utf-8"))["settings"]}
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise SystemExit(f"RUN: expected a bench worlds folder with its bench.json; got "
                         f"{args.run} ({exc})") from None
    if "modulus" not in settings["fields"] or settings["unread_place"] != "beta":
        raise SystemExit(f"RUN: expected a run on the modulus field with unread_place beta; got "
                         f"fields {settings['fields']}, unread_place "
                         f"{settings['unread_place']!r}")
    source = {}
    for path in sorted((args.run / "worlds").glob("world-*.json")):
        try:
            result = json.loads(path.read_text(encoding="utf-8"))
            if result.get("status") == "ok":
                source[result["world"]["index"]] = result
        except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:
            raise SystemExit(f"RUN: {path} is not a world's result ({exc})") from None
    affected = {i: _given_up(r) for i, r in source.items() if _given_up(r)}
    if not affected:
        raise SystemExit(f"RUN: no combination of {args.run} went to β for good; nothing to do")
    k = settings["max_pokes"]
    cut = settings["cuts"][0]
    if args.again:
        try:
            again = {r["world"]["index"]: r for r in json.loads(args.again.read_text("utf-8"))}
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise SystemExit(f"--again: expected a JSON file written by --out; got "
                             f"{args.again} ({exc})") from None
        if set(again) != set(affected):
            raise SystemExit(f"--again: expected the worlds {sorted(affected)}; got "
                             f"{sorted(again)}")
        print(f"{len(affected)} of {len(source)} worlds of {args.run} had a combination go to β "
              f"for good; read again from {args.again}")
    else:
        print(f"{len(affected)} of {len(source)} worlds of {args.run} had a combination go to β "
              f"for good; mapping them again with unread_place: avoid ({args.workers} "
              f"processes)")
        keys = ("seed", "families", "physics", "strategies", "fields", "cuts", "max_pokes",
                "coarse", "merge_seams", "split_by_place", "boundary_score")
        tasks = {i: {**{key: settings[key] for key in keys}, "index": i,
                     "unread_place": "avoid"} for i in affected}
        t0 = time.perf_counter()
        # bench worlds' own pool: BLAS on one thread, and workers that end with this process
        with worker_pool(args.workers) as pool:
            again = dict(zip(tasks, pool.map(run_world, tasks.values()), strict=True))
        print(f"mapped in {time.perf_counter() - t0:.0f} s\n")
        if args.out:
            args.out.write_text(json.dumps(list(again.values())), encoding="utf-8")

    paired = True
    for i, result in again.items():
        for strategy in settings["strategies"]:
            for field in settings["fields"]:
                combo = f"{strategy}/{field}"
                until = (_fell(_curve(source[i]["rows"], strategy, cut))
                         if (strategy, field) in affected[i] else k + 1)
                if not _same_pokes(source[i]["pokes"][combo], result["pokes"][combo], until):
                    paired = False
                    print(f"world {i}: {combo} pressed elsewhere than the run"
                          + (f" before poke {until}, where it fell back"
                             if until <= k else ""))
    print("the combinations that did not fall back pressed where the run did, with the same "
          "readings (to 1e-9), and those that did up to that poke" if paired else
          "NOT PAIRED: the combinations above pressed elsewhere")
    print()
    print(f"| world | family | strategy | fell back at | pokes to {GOOD} (beta / avoid) | "
          f"accuracy after the last poke (beta / avoid) | E error after the last poke (beta / "
          f"avoid) | pokes on β under avoid |")
    print("|---|---|---|---|---|---|---|---|")
    pairs = []
    for i in sorted(affected):
        for strategy, _ in sorted(affected[i]):
            old, new = _curve(source[i]["rows"], strategy, cut), _curve(again[i]["rows"],
                                                                        strategy, cut)
            fell = _fell(old)
            unread = sum(r["map_field"] == "beta" for r in new)
            combo = (strategy, "modulus", cut)
            pairs.append((pokes_to_good([source[i]], combo, k)[i],
                          pokes_to_good([again[i]], combo, k)[i], old[-1]["accuracy"],
                          new[-1]["accuracy"]))
            err = [c[-1]["modulus_error"] for c in (old, new)]
            print(f"| {i} | {source[i]['world']['family']} | {strategy} | {fell} | "
                  f"{pairs[-1][0]} / {pairs[-1][1]} | {old[-1]['accuracy']:.3f} / "
                  f"{new[-1]['accuracy']:.3f} | "
                  + " / ".join("–" if e is None else f"{e:.2f}" for e in err)
                  + f" | {unread} |")
    arr = np.array(pairs, dtype=float)
    better = int(np.sum(arr[:, 1] < arr[:, 0]))
    worse = int(np.sum(arr[:, 1] > arr[:, 0]))
    print(f"\n{len(pairs)} combinations: median pokes to {GOOD} {np.median(arr[:, 0]):g} (beta) "
          f"/ {np.median(arr[:, 1]):g} (avoid); fewer under avoid in {better}, more in {worse}; "
          f"mean final accuracy {arr[:, 2].mean():.3f} / {arr[:, 3].mean():.3f}")
    combos = [(s, "modulus", cut) for s in settings["strategies"]]
    before = summarise_worlds(list(source.values()), combos, k)["strategies"]
    after = summarise_worlds([again.get(i, r) for i, r in source.items()], combos,
                             k)["strategies"]
    print(f"\nThe whole run ({len(source)} worlds), median pokes to {GOOD} / reach:")
    print("| combination | unread_place: beta | unread_place: avoid |")
    print("|---|---|---|")
    for s, f, c in combos:
        name = f"{s}/{f}/{c}"
        b, a = before[name], after[name]
        print(f"| {name} | {b['median_pokes_to_accuracy_0.9']:g} / "
              f"{b['share_reaching_0.9']:.0%} | {a['median_pokes_to_accuracy_0.9']:g} / "
              f"{a['share_reaching_0.9']:.0%} |")


if __name__ == "__main__":
    main()
