#!/usr/bin/python3
"""Counts test cases in the JUnit XML files under a folder (gtest, rostest, rosunit).

Prints "N passed, N failed, N skipped" and exits 1 if any test case failed or none ran.
Every <testcase> counts once; one with a <failure> or <error> child failed, one with
<skipped> was skipped.
"""
import pathlib
import sys
import xml.etree.ElementTree as ElementTree


def main(folder):
    passed = failed = skipped = 0
    failures = []
    for path in sorted(pathlib.Path(folder).rglob("*.xml")):
        try:
            root = ElementTree.parse(path).getroot()
        except ElementTree.ParseError as error:
            failed += 1
            failures.append(f"{path.name}: unreadable result file ({error})")
            continue
        for case in root.iter("testcase"):
            name = f"{path.stem}: {case.get('classname', '')}.{case.get('name', '')}"
            if case.find("failure") is not None or case.find("error") is not None:
                failed += 1
                failures.append(name)
            elif case.find("skipped") is not None or case.get("status") == "notrun":
                skipped += 1
            else:
                passed += 1
    for name in failures:
        print(f"FAILED {name}")
    if passed + failed == 0:
        print("no test ran")
    print(f"{passed} passed, {failed} failed, {skipped} skipped")
    return 0 if failed == 0 and passed > 0 else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else "build/test_results"))
