#!/usr/bin/env python3
"""Draws a soak run's CSV (scripts/soak_monitor.py): the nodelet manager's resident memory and
each mapper's mean integration time per sampling interval, over the run.

Usage: soak_plot.py SOAK_CSV OUTPUT_PNG
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402 (after choosing the headless backend)

MAPPERS = ("depth_mapper", "disparity_mapper", "laser_mapper", "point_cloud_mapper")


def column(rows, name):
    """(elapsed minutes, value) of the rows where `name` has a value."""
    points = [(float(row["elapsed_s"]) / 60.0, float(row[name])) for row in rows if row.get(name)]
    return [p[0] for p in points], [p[1] for p in points]


def main(csv_path, png_path):
    with open(csv_path, newline="") as source:
        rows = list(csv.DictReader(source))
    figure, (memory, timing) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    minutes, rss = column(rows, "manager_rss_mb")
    memory.plot(minutes, rss, color="black", label="nodelet manager VmRSS")
    minutes, map_mb = column(rows, "map_memory_mb")
    memory.plot(minutes, map_mb, color="grey", linestyle="--", label="voxel map (memoryBytes)")
    memory.set_ylabel("MiB")
    memory.set_ylim(bottom=0)
    memory.legend(loc="lower right")
    memory.grid(alpha=0.3)
    for mapper in MAPPERS:
        minutes, mean_ms = column(rows, mapper + "_interval_mean_ms")
        if mean_ms:
            timing.plot(minutes, mean_ms, marker=".", label=mapper.replace("_", " "))
    timing.set_yscale("log")
    timing.set_ylabel("integration ms per frame\n(mean over each 5 s)")
    timing.set_xlabel("minutes (the demo bag played in a loop)")
    timing.legend(loc="upper right")
    timing.grid(alpha=0.3, which="both")
    figure.tight_layout()
    figure.savefig(png_path, dpi=80)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
