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

Usage: check_parameters_documented.py <package root>; exits 1 and lists the undocumented keys.
"""
import pathlib
import re
import sys

# Where the nodelets' parameters are read (the offline tools read the same YAML through the same
# readers).
SOURCE_GLOBS = ["src/ros/*.cpp", "src/nodelets/*.cpp", "src/integrators/*config_reader.cpp",
                "src/map/config_readers.cpp", "include/occupancy_fusion/params/*.h"]
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
    keys = {}
    for pattern in SOURCE_GLOBS:
        for path in sorted(root.glob(pattern)):
            text = path.read_text()
            prefixes = dict(PREFIX_CONSTANT.findall(text))
            for match in TRANSPORT_HINTS.finditer(text):
                keys.setdefault("image_transport", str(path.relative_to(root)))
            for regex in (GET_CALL, HELPER_CALL):
                for match in regex.finditer(text):
                    # A prefix held in a constant of this file is part of the key; one computed at
                    # run time (a source's name) is not known here: the rest of the key is then
                    # looked for under any path.
                    key = prefixes.get(match.group(1), "") + match.group(2)
                    # A key: path components of identifier characters (not messages or paths).
                    if re.fullmatch(r"[a-z_][a-z0-9_]*(/[a-z_][a-z0-9_]*)*", key):
                        line = text.count("\n", 0, match.start()) + 1
                        keys.setdefault(key, f"{path.relative_to(root)}:{line}")
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


def main():
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".").resolve()
    keys = keys_read(root)
    paths = documented_paths(root)
    # The extraction must find the parameters we know exist, or it has silently broken.
    for expected in ("queue_size", "publish_map", "sensor_model/hit", "observation_sources",
                     "depth/sigma", "laser/max_tilt", "image_transport"):
        if expected not in keys:
            print(f"extraction broken: '{expected}' not found in the sources")
            return 1
    missing = sorted(k for k in keys if not is_documented(k, paths))
    print(f"{len(keys)} parameter keys read in code, {len(paths)} key paths in config/*.yaml")
    for key in missing:
        print(f"undocumented: {key} (read at {keys[key]})")
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main())
