#!/usr/bin/env python3
"""Every figure of every scene test, before and after a change.

  compare_all_figures.py snapshot BUILD_DIR FILE.json   collect the figures of every
        summary.json a test run left under BUILD_DIR/tests (timings [s] and the rates
        measured with them, *_per_s*, left out)
  compare_all_figures.py compare BEFORE.json AFTER.json [--rel TOL]
        list every figure that differs (exactly, or beyond TOL relative); exit 1 if any
        does, or if a run or figure is missing on either side (new runs are listed only).

A refactoring that must not change results is checked by a snapshot of a full
`ctest -LE benchmark` run before and after it, then `compare`.
"""
import json
import math
import pathlib
import sys


def snapshot(build_dir, out_file):
    runs = {}
    for summary in sorted(pathlib.Path(build_dir, "tests").rglob("summary.json")):
        try:
            data = json.loads(summary.read_text())
        except (OSError, json.JSONDecodeError) as error:
            print(f"skipping {summary}: {error}", file=sys.stderr)
            continue
        name = str(summary.parent.relative_to(pathlib.Path(build_dir, "tests")))
        figures = {}
        for key, fig in data.get("figures", {}).items():
            if fig.get("unit") == "s" or "_per_s" in key:
                continue  # wall times and the rates measured with them differ run to run
            figures[key] = fig.get("value")
        runs[name] = {"status": data.get("status"), "figures": figures}
    pathlib.Path(out_file).write_text(json.dumps(runs, indent=1, sort_keys=True))
    n = sum(len(r["figures"]) for r in runs.values())
    print(f"{len(runs)} runs, {n} figures -> {out_file}")


def differs(a, b, rel):
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        if rel == 0:
            return a != b
        scale = max(abs(a), abs(b))
        return not math.isfinite(a - b) or abs(a - b) > rel * scale
    return a != b


def compare(before_file, after_file, rel):
    before = json.loads(pathlib.Path(before_file).read_text())
    after = json.loads(pathlib.Path(after_file).read_text())
    problems, compared = [], 0
    for run in sorted(set(before) | set(after)):
        if run not in before:
            print(f"{run}: new run (not compared)")
            continue
        if run not in after:
            problems.append(f"{run}: missing after")
            continue
        a, b = before[run], after[run]
        if a["status"] != b["status"]:
            problems.append(f"{run}: status {a['status']} -> {b['status']}")
        for key in sorted(set(a["figures"]) | set(b["figures"])):
            if key not in a["figures"] or key not in b["figures"]:
                problems.append(f"{run}/{key}: only {'before' if key in a['figures'] else 'after'}")
                continue
            compared += 1
            if differs(a["figures"][key], b["figures"][key], rel):
                problems.append(f"{run}/{key}: {a['figures'][key]!r} -> {b['figures'][key]!r}")
    for p in problems:
        print(p)
    print(f"{len(before)} runs, {compared} figures compared, {len(problems)} differences")
    return 1 if problems else 0


def main(argv):
    if len(argv) >= 4 and argv[1] == "snapshot":
        snapshot(argv[2], argv[3])
        return 0
    if len(argv) >= 4 and argv[1] == "compare":
        rel = float(argv[argv.index("--rel") + 1]) if "--rel" in argv else 0.0
        return compare(argv[2], argv[3], rel)
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))
