#!/usr/bin/env python3
"""Samples a running soak (scripts/soak.sh) every few seconds into a CSV file.

Per sample: the nodelet manager's resident memory (VmRSS) and CPU time, the MapServer's map size
and lock statistics, and per mapper the frames integrated and the mean integration time of the
frames integrated since the previous sample (from the cumulative 'integration ms (mean)' of
/diagnostics), so a slow drift shows instead of being averaged away. It also keeps every
published map output watched (subscribing without deserialising) so the MapServer builds them all,
and calls ~save_map every --save-every seconds.

Usage: soak_monitor.py --manager NAME --duration S --csv FILE --save-prefix PREFIX
"""
import argparse
import csv
import os
import sys
import time

import rospy
from graph_probe import Diagnostics, cpu_seconds, node_pid
from occupancy_fusion.srv import SaveMap

MAPPERS = ("depth_mapper", "disparity_mapper", "laser_mapper", "point_cloud_mapper")
WATCHED_TOPICS = ("projected_map", "occupied_cells_vis_array", "octomap_point_cloud_centers",
                  "octomap_binary")


def resident_mb(pid):
    with open("/proc/%d/status" % pid) as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    raise RuntimeError("no VmRSS for pid %d" % pid)


def save_map(service, prefix):
    """Calls ~save_map; whether it succeeded and how long the call took (s)."""
    started = time.monotonic()
    try:
        response = service(prefix=prefix)
        ok = response.success
        if not ok:
            rospy.logwarn("save_map failed: %s", response.message)
    except rospy.ServiceException as error:
        rospy.logwarn("save_map failed: %s", error)
        ok = False
    return ok, time.monotonic() - started


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--manager", default="/occupancy_fusion_manager")
    parser.add_argument("--duration", type=float, required=True)
    parser.add_argument("--period", type=float, default=5.0)
    parser.add_argument("--save-every", type=float, default=5.0)
    parser.add_argument("--save-prefix", required=True)
    parser.add_argument("--csv", required=True)
    args = parser.parse_args(rospy.myargv()[1:])

    rospy.init_node("soak_monitor", disable_signals=True)
    diagnostics = Diagnostics()
    watchers = [rospy.Subscriber(topic, rospy.AnyMsg, lambda _: None, queue_size=1)
                for topic in WATCHED_TOPICS]
    pid = node_pid(args.manager, "/soak_monitor")
    rospy.wait_for_service("/map_server/save_map", 60)
    save_service = rospy.ServiceProxy("/map_server/save_map", SaveMap)

    columns = ["elapsed_s", "manager_rss_mb", "manager_cpu_s", "map_blocks", "map_memory_mb",
               "longest_lock_hold_ms", "longest_lock_hold_call", "longest_read_wait_ms",
               "saves_ok", "saves_failed", "longest_save_call_s"]
    for mapper in MAPPERS:
        columns += [mapper + "_integrated", mapper + "_interval_mean_ms", mapper + "_max_ms",
                    mapper + "_time_jumps_back"]
    previous = {mapper: (0, 0.0) for mapper in MAPPERS}  # integrated, total ms
    saves_ok = saves_failed = 0
    longest_save = 0.0
    start = time.monotonic()
    next_save = start + args.save_every
    next_sample = start
    with open(args.csv, "w", newline="") as out:
        writer = csv.DictWriter(out, fieldnames=columns)
        writer.writeheader()
        while not rospy.is_shutdown():
            now = time.monotonic()
            if now >= next_save:
                ok, seconds = save_map(save_service, args.save_prefix)
                saves_ok += ok
                saves_failed += not ok
                longest_save = max(longest_save, seconds)
                next_save = time.monotonic() + args.save_every
            if now >= next_sample:
                row = {"elapsed_s": round(now - start, 1),
                       "manager_rss_mb": round(resident_mb(pid), 2),
                       "manager_cpu_s": round(cpu_seconds(pid), 2),
                       "saves_ok": saves_ok, "saves_failed": saves_failed,
                       "longest_save_call_s": round(longest_save, 3)}
                server = diagnostics.find("map_server", "longest lock hold (ms)")
                if server:
                    row["map_blocks"] = server.get("map blocks")
                    row["map_memory_mb"] = round(float(server.get("memory bytes", 0)) / 2**20, 2)
                    row["longest_lock_hold_ms"] = server["longest lock hold (ms)"]
                    row["longest_lock_hold_call"] = server.get("longest lock hold (call)")
                    row["longest_read_wait_ms"] = server.get("longest wait for a read (ms)")
                for mapper in MAPPERS:
                    values = diagnostics.find(mapper, "integration ms (mean)")
                    if not values:
                        continue
                    integrated = int(values["frames integrated"])
                    total = integrated * float(values["integration ms (mean)"])
                    done, done_total = previous[mapper]
                    row[mapper + "_integrated"] = integrated
                    if integrated > done:
                        row[mapper + "_interval_mean_ms"] = round(
                            (total - done_total) / (integrated - done), 3)
                    row[mapper + "_max_ms"] = values["integration ms (max)"]
                    row[mapper + "_time_jumps_back"] = values.get(
                        "time jumps back (tf buffer cleared)", "")
                    previous[mapper] = (integrated, total)
                writer.writerow(row)
                out.flush()
                next_sample += args.period
            if now - start >= args.duration:
                break
            time.sleep(0.2)
    del watchers
    return 0


if __name__ == "__main__":
    sys.exit(main())
