#!/usr/bin/env python3
"""Draws a robot-budget run's CSV (scripts/robot_budget_monitor.py) over time: per sensor topic
the median and 99th-percentile latency from a frame's stamp to the first projected_map holding it,
and the CPU share of the mapping manager and of rosbag play.

Usage: robot_budget_plot.py ROBOT_BUDGET_CSV OUTPUT_PNG
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402 (after choosing the headless backend)


def series(rows, name):
    """(elapsed s, value) of the rows where `name` has a value."""
    points = [(float(row["elapsed_s"]), float(row[name])) for row in rows if row.get(name)]
    return [p[0] for p in points], [p[1] for p in points]


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    with open(sys.argv[1], newline="") as source:
        rows = list(csv.DictReader(source))
    if not rows:
        sys.exit("robot_budget_plot.py: %s has no rows" % sys.argv[1])
    topics = [name[: -len(" latency_median_ms")] for name in rows[0]
              if name.endswith(" latency_median_ms")]
    figure, (latency, cpu) = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    for index, topic in enumerate(topics):
        colour = "C%d" % index
        latency.plot(*series(rows, topic + " latency_median_ms"), color=colour, label=topic + " median")
        latency.plot(*series(rows, topic + " latency_p99_ms"), color=colour, linestyle=":",
                     label=topic + " p99")
    # The budget's goals: median latency 40 ms, p99 100 ms, the manager 35 % of the cores.
    latency.axhline(40, color="grey", linewidth=0.8)
    latency.axhline(100, color="grey", linewidth=0.8, linestyle=":")
    latency.set_ylabel("stamp to projected_map (ms)")
    latency.legend(fontsize=7, ncol=2)
    for name, colour in (("manager_cpu_share", "C0"), ("player_cpu_share", "C3")):
        x, y = series(rows, name)
        cpu.plot(x, [100 * v for v in y], color=colour, label=name.replace("_cpu_share", ""))
    cpu.axhline(35, color="grey", linewidth=0.8)
    cpu.set_ylabel("CPU (% of all cores)")
    cpu.set_xlabel("time (s, per window)")
    cpu.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(sys.argv[2], dpi=100)


if __name__ == "__main__":
    main()
