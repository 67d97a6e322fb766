#!/usr/bin/env python3
"""Draws two `benchmark spill` runs (--csv) of the same building, one without a memory bound and
one with it: resident memory (anonymous, and the store's file-backed pages) and the map's own
accounting against the distance driven, and the integration time per frame (a moving median over
201 frames), with the bound drawn in.

Usage: spill_run_plot.py UNBOUNDED_CSV BOUNDED_CSV BOUND_MIB OUTPUT_PNG
"""
import csv
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402 (after choosing the headless backend)


def read(path):
    with open(path, newline="") as source:
        rows = list(csv.DictReader(source))
    if not rows:
        sys.exit("spill_run_plot.py: %s has no rows" % path)
    return rows


def column(rows, name):
    return [float(row[name]) for row in rows]


def moving_median(values, window=201):
    half = window // 2
    return [statistics.median(values[max(0, i - half): i + half + 1]) for i in range(len(values))]


def main():
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    unbounded, bounded = read(sys.argv[1]), read(sys.argv[2])
    bound = float(sys.argv[3])
    figure, (memory, time) = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    for rows, label, colour in ((unbounded, "no bound", "C0"), (bounded, "bound", "C1")):
        x = column(rows, "travelled_m")
        memory.plot(x, column(rows, "rss_anon_mb"), color=colour, label=label + ": resident (anonymous)")
        memory.plot(x, column(rows, "map_mb"), color=colour, linestyle=":", label=label + ": map's accounting")
        time.plot(x, moving_median(column(rows, "integrate_ms")), color=colour, label=label)
    memory.plot(column(bounded, "travelled_m"), column(bounded, "rss_file_mb"), color="C2",
                linestyle="--", label="bound: file-backed resident (libraries, then store pages)")
    memory.axhline(bound, color="grey", linewidth=0.8, label="bound %.0f MiB" % bound)
    memory.set_ylabel("MiB")
    memory.legend(fontsize=8, loc="upper left")
    time.set_ylabel("integration ms / frame\n(moving median of 201)")
    time.set_xlabel("distance travelled (m)")
    time.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(sys.argv[4], dpi=90)


if __name__ == "__main__":
    main()
