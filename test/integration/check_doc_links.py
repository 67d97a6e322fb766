#!/usr/bin/env python3
"""Checks that every relative link and anchor in README.md and docs/*.md resolves.

A link is an inline link or image (`[text](target)`, `![alt](images/x.png)`, with an optional
title), a reference definition (`[name]: target`) or an HTML `<a href>` / `<img src>`; links in
fenced code blocks and code spans are not links. External targets (any scheme: http, https,
mailto, ...) are not checked. The others must resolve as GitHub resolves them: the file or folder
exists, relative to the page (a leading `/`: to the package root), without leaving the package;
an anchor (`file.md#anchor`, `#anchor` on the page itself) must be the slug of a heading of the
target page by GitHub's rules (markdown and HTML removed, lowercase, punctuation but hyphens,
underscores and spaces removed, each space a hyphen; a repeated slug gets -1, -2, ...) or an
`<a name>` / `id` anchor there. Anchors into other files (`x.cpp#L10`) are not checked.

Usage: check_doc_links.py <package root> [--junit FILE.xml]; prints each broken link with its page
and line and exits 1 if any. With --junit it also writes JUnit XML (as the gtests do, into
catkin's test_results folder, where scripts/count_test_results.py counts it): one test case per
page, failing with that page's broken links, and one that fails when the extraction no longer
finds a link known to exist.
"""
import pathlib
import re
import sys
import urllib.parse

import junit_report  # beside this script

PAGE_GLOBS = ["README.md", "docs/*.md"]
# A link known to exist: README.md's link to the user guide (the extraction must find it).
EXPECTED_LINK = ("README.md", "docs/user_guide.md")

FENCE = re.compile(r"^ {0,3}(`{3,}|~{3,})")
ATX_HEADING = re.compile(r"^ {0,3}(#{1,6})(?:[ \t]+(.*?))?(?:[ \t]+#+)?[ \t]*$")
SETEXT_UNDERLINE = re.compile(r"^ {0,3}(=+|-+)[ \t]*$")
CODE_SPAN = re.compile(r"(`+)(.+?)\1", re.S)
# [text](target "title") and ![alt](target); the text may hold one level of brackets.
INLINE_LINK = re.compile(
    r"!?\[(?:[^\[\]]|\[[^\[\]]*\])*\]\(\s*(<[^>]*>|(?:[^()\s]|\([^()\s]*\))*)"
    r"(?:\s+(?:\"[^\"]*\"|'[^']*'|\([^)]*\)))?\s*\)")
REFERENCE_DEFINITION = re.compile(r"^ {0,3}\[[^\]]+\]:\s*(<[^>]*>|\S+)", re.M)
HTML_LINK = re.compile(r"<(?:a|img)\b[^>]*?\b(?:href|src)\s*=\s*(\"[^\"]*\"|'[^']*')", re.I)
HTML_ANCHOR = re.compile(r"<[a-z]+\b[^>]*?\b(?:name|id)\s*=\s*(\"[^\"]*\"|'[^']*')", re.I)
SCHEME = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]*:")


def prose_lines(text):
    """(line number, line) of the lines outside fenced code blocks."""
    fence = None
    for number, line in enumerate(text.splitlines(), start=1):
        match = FENCE.match(line)
        if fence is None:
            if match:
                fence = match.group(1)
                continue
            yield number, line
        elif match and match.group(1)[0] == fence[0] and len(match.group(1)) >= len(fence) \
                and not line.strip()[len(match.group(1)):].strip():
            fence = None


def blank_code_spans(text):
    """The text with each code span replaced by spaces (line breaks kept): no link is found
    inside one."""
    return CODE_SPAN.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), text)


def paragraphs(text):
    """(first line number, text) of each run of prose lines between blank lines and code blocks,
    so that a link whose text wraps onto the next line is found."""
    current, start, last = [], None, None
    for number, line in prose_lines(text):
        if current and (not line.strip() or number != last + 1):
            yield start, "\n".join(current)
            current = []
        if line.strip():
            if not current:
                start = number
            current.append(line)
        last = number
    if current:
        yield start, "\n".join(current)


def heading_text(markdown):
    """A heading's text as rendered: links and images by their text, code, emphasis and HTML
    tags without their markup."""
    text = re.sub(r"!?\[((?:[^\[\]]|\[[^\[\]]*\])*)\]\([^)]*\)", r"\1", markdown)
    text = re.sub(r"<[^>]+>", "", text)
    return text.strip()


def slug(text):
    """GitHub's anchor for a heading's rendered text (github-slugger, before the -N suffix)."""
    return re.sub(r"[^\w\- ]", "", text.lower()).replace(" ", "-")


def anchors_of(text):
    """Every anchor a page defines: its headings' slugs (repeats numbered) and HTML name/id."""
    anchors = set()
    counts = {}

    def add_heading(markdown):
        base = slug(heading_text(markdown))
        candidate = base
        while candidate in counts:
            counts[base] += 1
            candidate = f"{base}-{counts[base]}"
        counts.setdefault(candidate, 0)
        anchors.add(candidate)

    previous = None  # the previous prose line, when it could be a setext heading's text
    for _, line in prose_lines(text):
        for match in HTML_ANCHOR.finditer(line):
            anchors.add(match.group(1)[1:-1])
        atx = ATX_HEADING.match(line)
        if atx:
            add_heading(atx.group(2) or "")
            previous = None
            continue
        if previous is not None and SETEXT_UNDERLINE.match(line):
            add_heading(previous)
            previous = None
            continue
        stripped = line.strip()
        plain = stripped and not stripped.startswith(("|", ">", "-", "*", "+", "<")) \
            and not re.match(r"\d+[.)]\s", stripped) and not line.startswith(("    ", "\t"))
        previous = stripped if plain else None
    return anchors


def links_of(text):
    """(line number, target) of every link of a page, in order of the regexes per paragraph."""
    links = []
    for start, paragraph in paragraphs(text):
        prose = blank_code_spans(paragraph)
        for regex in (INLINE_LINK, REFERENCE_DEFINITION, HTML_LINK):
            for match in regex.finditer(prose):
                target = match.group(1)
                if target[:1] in "<\"'" and target[-1:] in ">\"'":
                    target = target[1:-1]
                links.append((start + prose.count("\n", 0, match.start(1)), target))
    return sorted(links, key=lambda link: link[0])


class Resolver:
    def __init__(self, root):
        self.root = root
        self.anchor_cache = {}

    def anchors(self, path):
        if path not in self.anchor_cache:
            self.anchor_cache[path] = anchors_of(path.read_text(encoding="utf-8"))
        return self.anchor_cache[path]

    def problem(self, page, target):
        """Why `target` on `page` does not resolve, or None when it does (or is external)."""
        if not target:
            return "empty link"
        if SCHEME.match(target) or target.startswith("//"):
            return None
        path_part, _, anchor = target.partition("#")
        path_part = urllib.parse.unquote(path_part.split("?", 1)[0])
        anchor = urllib.parse.unquote(anchor)
        if path_part:
            base = self.root if path_part.startswith("/") else page.parent
            resolved = (base / path_part.lstrip("/")).resolve()
            try:
                shown = resolved.relative_to(self.root)
            except ValueError:
                return f"'{path_part}' leaves the package"
            if not resolved.exists():
                return f"no file {shown}"
        else:
            resolved, shown = page, page.relative_to(self.root)
        if not anchor and "#" in target:
            return "empty anchor"
        if anchor and resolved.is_file() and resolved.suffix.lower() in (".md", ".markdown"):
            if anchor not in self.anchors(resolved):
                return f"no heading with anchor '#{anchor}' in {shown}"
        return None


def pages_of(root):
    pages = []
    for pattern in PAGE_GLOBS:
        pages += sorted(root.glob(pattern))
    return pages


def write_junit(path, results, extraction_problems):
    """One test case per page (its broken links as the failure), one for the extraction."""
    cases = [("extraction", extraction_problems, None)]
    cases += [(page, [f"line {line}: ({target}) {why}" for line, target, why in broken], None)
              for page, broken in results]
    junit_report.write_suite(path, "doc_links", cases, "broken")


def main():
    root, junit = junit_report.check_arguments(__doc__)
    resolver = Resolver(root)
    results = []  # (page, [(line, target, why)])
    total = checked = 0
    found_expected = False
    for page in pages_of(root):
        name = str(page.relative_to(root))
        broken = []
        for line, target in links_of(page.read_text(encoding="utf-8")):
            total += 1
            if (name, target.partition("#")[0]) == EXPECTED_LINK:
                found_expected = True
            if not SCHEME.match(target):
                checked += 1
            why = resolver.problem(page, target)
            if why:
                broken.append((line, target, why))
                print(f"{name}:{line}: broken link ({target}): {why}")
        results.append((name, broken))
    extraction_problems = []
    if not found_expected:
        extraction_problems.append(f"the link from {EXPECTED_LINK[0]} to {EXPECTED_LINK[1]} "
                                   "was not found: the extraction is broken")
    for problem in extraction_problems:
        print(f"extraction broken: {problem}")
    broken_count = sum(len(broken) for _, broken in results)
    print(f"{len(results)} pages, {total} links, {checked} relative links checked, "
          f"{broken_count} broken")
    if junit:
        write_junit(junit, results, extraction_problems)
    return 1 if broken_count or extraction_problems else 0


if __name__ == "__main__":
    sys.exit(main())
