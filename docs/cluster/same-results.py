#!/usr/bin/env python3
"""Checks that two `cargo xtask compare` output directories (e.g. a merged sharded run and an
unsharded run of the same settings) hold the same results: results.csv row for row in every
column but the times (`seconds_*`), as crates/compare/src/shard/tests.rs checks, and the
error columns of profiles.csv and kernels.csv (all but those named for seconds or ns).

    docs/cluster/same-results.py [--subset] EXPECTED_DIR ACTUAL_DIR

With --subset, EXPECTED_DIR is a run of fewer scenes or presets than ACTUAL_DIR (e.g.
`--quick --scenes sphere --presets skin1` against `--quick`): every one of its rows must be
in ACTUAL_DIR's tables with the same values (times aside). A unit's results do not depend on
which other scenes or presets share the run (each scene's seed, reference and exposure are
its own), so a cheap run checks the rows it has of an expensive one.
"""
import csv
import sys
from pathlib import Path


def timing(name, table):
    if table == "results.csv":
        return name.startswith("seconds_")
    return "seconds" in name or "ns_" in name or "_ns" in name


def compare(a_dir, b_dir, table, required, subset=False):
    a_path, b_path = Path(a_dir, table), Path(b_dir, table)
    if not required and not a_path.exists() and not b_path.exists():
        return []
    for p in (a_path, b_path):
        if not p.exists():
            return [f"{p}: missing"]
    a = list(csv.reader(a_path.open(newline="")))
    b = list(csv.reader(b_path.open(newline="")))
    if not a or a[0] != (b[0] if b else None):
        return [f"{table}: other columns: {a[:1]} against {b[:1]}"]
    header, errors = a[0], []
    if subset:
        keep = [i for i, col in enumerate(header) if not timing(col, table)]
        have = {tuple(r[i] for i in keep) for r in b[1:]}
        for n, ra in enumerate(a[1:], start=2):
            if tuple(ra[i] for i in keep) not in have:
                row = ",".join(ra[:5])
                errors.append(f"{table} line {n} ({row}) of {a_dir}: not in {b_dir} with the same values")
        return errors
    if len(a) != len(b):
        return [f"{table}: {len(a) - 1} rows in {a_dir}, {len(b) - 1} in {b_dir}"]
    for n, (ra, rb) in enumerate(zip(a[1:], b[1:]), start=2):
        for col, va, vb in zip(header, ra, rb):
            if va != vb and not timing(col, table):
                # The row named by its key: scene, method, param, value, threads.
                row = ",".join(ra[:5])
                errors.append(f"{table} line {n} ({row}), column {col}: {va!r} != {vb!r}")
    return errors


def main():
    args = sys.argv[1:]
    subset = args[:1] == ["--subset"]
    if subset:
        args = args[1:]
    if len(args) != 2:
        sys.exit(f"usage: {sys.argv[0]} [--subset] EXPECTED_DIR ACTUAL_DIR")
    a, b = args
    errors = compare(a, b, "results.csv", True, subset)
    for table in ("profiles.csv", "kernels.csv"):
        errors += compare(a, b, table, False, subset)
    if errors:
        print(f"same-results: {a} and {b} differ ({len(errors)} values):", file=sys.stderr)
        for e in errors[:20]:
            print("  " + e, file=sys.stderr)
        sys.exit(1)
    rows = sum(1 for _ in Path(a, "results.csv").open()) - 1
    if subset:
        print(f"same-results: {b} holds every row of {a} ({rows} rows of results.csv, times aside)")
    else:
        print(f"same-results: {b} equals {a} ({rows} rows of results.csv, times aside)")


if __name__ == "__main__":
    main()
