#!/usr/bin/env python3
"""Names the frames a ThreadSanitizer report left as '<null> <null> (library.so+0xOFFSET)' with
addr2line (the runtime's own symbolizer fails in processes it was preloaded into).

Usage: symbolize.py LIBRARY_FOLDER REPORT_FILE... (prints the reports with the frames named;
libraries named without a folder are looked up in LIBRARY_FOLDER)
"""
import os
import re
import subprocess
import sys

FRAME = re.compile(r"^(\s+#\d+ )<null> <null> \((\S+\.so[.\w]*)\+(0x[0-9a-f]+)\)$")


def name(library, offset, cache={}):
    key = (library, offset)
    if key not in cache:
        result = subprocess.run(["addr2line", "-f", "-C", "-e", library, offset],
                                capture_output=True, text=True)
        lines = result.stdout.splitlines()
        cache[key] = "%s %s" % (lines[0], lines[1]) if len(lines) >= 2 else "<null>"
    return cache[key]


def main(library_folder, paths):
    for path in paths:
        with open(path) as report:
            for line in report:
                match = FRAME.match(line.rstrip("\n"))
                library = match and os.path.join(library_folder, match.group(2))
                if match and os.path.exists(library):
                    line = "%s%s (%s+%s)\n" % (match.group(1), name(library, match.group(3)),
                                               match.group(2), match.group(3))
                sys.stdout.write(line)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2:])
