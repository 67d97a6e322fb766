"""What the integration checks share: their command line, and JUnit XML in the form
scripts/count_test_results.py counts.

check_arguments(doc): the package root (resolved) and the --junit file (or None).
write_suite(path, suite_name, cases): cases are (name, problems, skipped) with problems a list
of strings (a failure when not empty) and skipped a reason or None.
"""
import argparse
import pathlib
import xml.etree.ElementTree as ElementTree


def check_arguments(doc):
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("root", nargs="?", default=".", help="package root")
    parser.add_argument("--junit", help="also write the result as JUnit XML to this file")
    arguments = parser.parse_args()
    return pathlib.Path(arguments.root).resolve(), arguments.junit


def write_suite(path, suite_name, cases, problem_word="problems"):
    suite = ElementTree.Element("testsuite", name=suite_name)
    for name, problems, skipped in cases:
        case = ElementTree.SubElement(suite, "testcase", classname=suite_name, name=name)
        if problems:
            failure = ElementTree.SubElement(case, "failure",
                                             message=f"{len(problems)} {problem_word}")
            failure.text = "\n".join(problems)
        elif skipped:
            ElementTree.SubElement(case, "skipped", message=skipped)
    suite.set("tests", str(len(cases)))
    suite.set("failures", str(sum(1 for _, problems, _ in cases if problems)))
    suite.set("skipped", str(sum(1 for _, problems, skipped in cases if skipped and not problems)))
    suite.set("errors", "0")
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    ElementTree.ElementTree(suite).write(path, encoding="utf-8", xml_declaration=True)
