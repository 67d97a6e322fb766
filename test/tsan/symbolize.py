#!/usr/bin/env python3
"""Names the frames a ThreadSanitizer report left as '<null> <null> (library.so+0xOFFSET)' with
addr2line (the runtime's own symbolizer fails in processes it was preloaded into), functions
inlined at that address included ('[inlined into ...]'). The runtime matches its suppressions
before this naming, so a race whose distinguishing frames are all in the project's library cannot
be suppressed there: --suppressions FILE leaves out the reports with a line containing one of the
FILE's patterns (one per line, '#' starts a comment) and says how many on stderr.

Usage: symbolize.py [--suppressions FILE] LIBRARY_FOLDER REPORT_FILE... (prints the reports with
the frames named; libraries named without a folder are looked up in LIBRARY_FOLDER)
"""
import argparse
import os
import re
import subprocess
import sys

FRAME = re.compile(r"^(\s+#\d+ )<null> <null> \((\S+\.so[.\w]*)\+(0x[0-9a-f]+)\)$")
SEPARATOR = "=================="


def name(library, offset, cache={}):
    """'function location', innermost inlined function first, or '<null>'."""
    key = (library, offset)
    if key not in cache:
        result = subprocess.run(["addr2line", "-f", "-C", "-i", "-e", library, offset],
                                capture_output=True, text=True)
        lines = result.stdout.splitlines()
        pairs = [(lines[i], lines[i + 1]) for i in range(0, len(lines) - 1, 2)]
        if not pairs:
            cache[key] = "<null>"
        else:
            text = "%s %s" % pairs[0]
            if len(pairs) > 1:
                text += " [inlined into %s]" % "; ".join(function for function, _ in pairs[1:])
            cache[key] = text
    return cache[key]


def named_lines(library_folder, path):
    with open(path) as report:
        for line in report:
            match = FRAME.match(line.rstrip("\n"))
            library = match and os.path.join(library_folder, match.group(2))
            if match and os.path.exists(library):
                line = "%s%s (%s+%s)\n" % (match.group(1), name(library, match.group(3)),
                                           match.group(2), match.group(3))
            yield line


def read_patterns(path):
    patterns = []
    with open(path) as lines:
        for line in lines:
            line = line.split("#", 1)[0].strip()
            if line:
                patterns.append(line)
    return patterns


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suppressions")
    parser.add_argument("library_folder")
    parser.add_argument("reports", nargs="+")
    arguments = parser.parse_args()
    patterns = read_patterns(arguments.suppressions) if arguments.suppressions else []
    left_out = 0
    for path in arguments.reports:
        block = None  # the lines of the report being read, between two separators
        for line in named_lines(arguments.library_folder, path):
            if line.rstrip("\n") == SEPARATOR:
                if block is None:
                    block = [line]
                    continue
                block.append(line)
                if any(pattern in text for text in block for pattern in patterns):
                    left_out += 1
                else:
                    sys.stdout.writelines(block)
                block = None
            elif block is not None:
                block.append(line)
            else:
                sys.stdout.write(line)
        if block is not None:
            sys.stdout.writelines(block)
    if patterns:
        sys.stderr.write("%d report(s) left out: they match %s\n" % (left_out, arguments.suppressions))


if __name__ == "__main__":
    main()
