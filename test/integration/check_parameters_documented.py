#!/usr/bin/env python3
"""Checks that every ROS parameter the code reads is documented in config/*.yaml.

The keys are taken from the source, not from a list: every string literal passed as a key to a
ParameterSource (`<source>.get("key", ...)`, `<source>.get(prefix + "key", ...)`) or to one of the
readers' helpers that take the source first (`read(source, "key", ...)`,
`readChecked(source, prefix, "key", ...)`). A key is documented when a config file holds it, set
or commented out ("# fx: 262.4"), under a path that ends with the key (a key read under a prefix,
"noise/" + "seed", is found as stereo/noise/seed; a prefix held in a string constant of the same
file, kKeyPrefix = "depth/", is resolved). image_transport's ~image_transport, read by the
library through the TransportHints the depth mapper passes its private node handle, is included.

Usage: check_parameters_documented.py <package root> [--junit FILE.xml]; exits 1 and lists the
undocumented keys. With --junit it also writes JUnit XML (as the gtests do, into catkin's
test_results folder, where scripts/count_test_results.py counts it): one test case per source
file that reads parameters, failing with that file's undocumented keys, and one that fails when
the extraction no longer finds the keys known to exist.
"""
import pathlib
import re
import sys

import junit_report  # beside this script

# Where the nodelets' parameters are read (the offline tools read the same YAML through the same
# readers).
SOURCE_GLOBS = ["src/ros/*.cpp", "src/nodelets/*.cpp", "src/nodelets/simulator/*.cpp",
                "src/params/*.cpp", "include/occupancy_fusion/params/*.h"]
STRING = r'"((?:[^"\\]|\\.)*)"'
# source.get("key" / prefix + "key"; the source object is any identifier.
GET_CALL = re.compile(r"\b\w+\s*(?:\.|->)\s*get\(\s*(?:([\w:]+)(?:\(\))?\s*\+\s*)?" + STRING)
# helper(source, "key" / helper(source, prefix, "key" / helper(source, prefix + "key".
HELPER_CALL = re.compile(
    r"\b\w+\(\s*(?:source|parameters)\s*,\s*(?:([\w:]+)\s*(?:,|\+)\s*)?" + STRING)
# image_transport::TransportHints(..., <private node handle>) reads ~image_transport.
TRANSPORT_HINTS = re.compile(r"TransportHints\(\s*\"\w+\"\s*,[^;]*,\s*getPrivateNodeHandle\(\)\s*\)")
# A key prefix held in a constant (named kSomething, as the style guide names constants):
# kKeyPrefix = "depth/", kSharedLaserPrefix[] = "laser/".
PREFIX_CONSTANT = re.compile(r"\b(k[A-Z]\w*)(?:\[\])?\s*=\s*\"([a-z_]+(?:/[a-z_]+)*/)\"")
YAML_KEY = re.compile(r"^(\s*)(#\s*)?([A-Za-z_][\w]*)\s*:(?:\s|$)")


def keys_read(root):
    """Every key read in code: {key: [(source file, line), ...]} in the order found."""
    keys = {}
    for pattern in SOURCE_GLOBS:
        for path in sorted(root.glob(pattern)):
            text = path.read_text()
            prefixes = dict(PREFIX_CONSTANT.findall(text))
            for match in TRANSPORT_HINTS.finditer(text):
                line = text.count("\n", 0, match.start()) + 1
                keys.setdefault("image_transport", []).append((str(path.relative_to(root)), line))
            for regex in (GET_CALL, HELPER_CALL):
                for match in regex.finditer(text):
                    # A prefix held in a constant of this file is part of the key; one computed at
                    # run time (a source's name) is not known here: the rest of the key is then
                    # looked for under any path.
                    key = prefixes.get(match.group(1), "") + match.group(2)
                    # A key: path components of identifier characters (not messages or paths).
                    if re.fullmatch(r"[a-z_][a-z0-9_]*(/[a-z_][a-z0-9_]*)*", key):
                        line = text.count("\n", 0, match.start()) + 1
                        keys.setdefault(key, []).append((str(path.relative_to(root)), line))
    return keys


def documented_paths(root):
    """Every key path of config/*.yaml, commented-out keys included ('a/b/c')."""
    paths = set()
    for path in sorted(root.glob("config/*.yaml")):
        stack = []  # (indent, key)
        for line in path.read_text().splitlines():
            match = YAML_KEY.match(line)
            if not match:
                continue
            indent = len(match.group(1))
            if match.group(2):  # a commented key sits at the indentation of its '#'
                indent = len(match.group(1))
            while stack and stack[-1][0] >= indent:
                stack.pop()
            stack.append((indent, match.group(3)))
            paths.add("/".join(key for _, key in stack))
    return paths


def is_documented(key, paths):
    return any(p == key or p.endswith("/" + key) for p in paths)


EXPECTED_KEYS = ("queue_size", "publish_map", "sensor_model/hit", "observation_sources",
                 "depth/sigma", "laser/max_tilt", "image_transport")


def write_junit(path, keys, missing, extraction_missing):
    """One test case per source file (its undocumented keys as the failure), one for extraction."""
    by_file = {}
    for key, places in keys.items():
        for source, line in places:
            by_file.setdefault(source, [])
            if key in missing:
                by_file[source].append(f"{key} (line {line})")
    cases = [("extraction", [f"'{key}' not found in the sources" for key in extraction_missing],
              None)]
    cases += [(source, undocumented, None) for source, undocumented in sorted(by_file.items())]
    junit_report.write_suite(path, "parameters_documented", cases, "undocumented")


def main():
    root, junit = junit_report.check_arguments(__doc__)
    keys = keys_read(root)
    paths = documented_paths(root)
    # The extraction must find the parameters we know exist, or it has silently broken.
    extraction_missing = [key for key in EXPECTED_KEYS if key not in keys]
    for key in extraction_missing:
        print(f"extraction broken: '{key}' not found in the sources")
    missing = sorted(k for k in keys if not is_documented(k, paths))
    print(f"{len(keys)} parameter keys read in code, {len(paths)} key paths in config/*.yaml")
    for key in missing:
        source, line = keys[key][0]
        print(f"undocumented: {key} (read at {source}:{line})")
    if junit:
        write_junit(junit, keys, set(missing), extraction_missing)
    return 1 if missing or extraction_missing else 0


if __name__ == "__main__":
    sys.exit(main())
