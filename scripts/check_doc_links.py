#!/usr/bin/env python3
"""Every relative link and image in the repository's Markdown files resolves: the file (or
folder) exists in the repository, and a `#anchor` names a heading of that file, spelled as
GitHub spells heading anchors. Links to http(s)/mailto are not followed (nothing here goes on
the network). Prints each broken link as FILE:LINE: LINK: why, exits 1 if there is one.

Usage: check_doc_links.py [REPO]   (default: this script's repository)"""
import os
import re
import sys

LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
HTML_ID = re.compile(r"<a\s+(?:id|name)=\"([^\"]+)\"")
SKIP_DIRS = {".git", "third_party", "node_modules"}


def anchor(heading):
    """GitHub's anchor of a heading: lower case, markup dropped, spaces to '-', punctuation
    other than '-' and '_' dropped."""
    text = re.sub(r"`([^`]*)`", r"\1", heading)
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", text)
    text = text.strip().lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(path):
    """The anchors of a Markdown file's headings (repeats get -1, -2 as on GitHub) and of its
    `<a id="...">` tags, outside code blocks."""
    seen = {}
    found = set()
    fenced = False
    with open(path, encoding="utf-8") as f:
        for line in f:
            if line.lstrip().startswith("```"):
                fenced = not fenced
                continue
            if fenced:
                continue
            found.update(HTML_ID.findall(line))
            m = HEADING.match(line)
            if not m:
                continue
            a = anchor(m.group(2))
            n = seen.get(a, 0)
            seen[a] = n + 1
            found.add(a if n == 0 else "%s-%d" % (a, n))
    return found


def markdown_files(repo):
    for root, dirs, files in os.walk(repo):
        dirs[:] = sorted(d for d in dirs if d not in SKIP_DIRS and not d.startswith("."))
        for name in sorted(files):
            if name.endswith(".md"):
                yield os.path.join(root, name)


def check(repo):
    problems = []
    for path in markdown_files(repo):
        rel = os.path.relpath(path, repo)
        fenced = False
        with open(path, encoding="utf-8") as f:
            lines = f.readlines()
        for number, line in enumerate(lines, 1):
            if line.lstrip().startswith("```"):
                fenced = not fenced
                continue
            if fenced:
                continue
            for target in LINK.findall(re.sub(r"`[^`]*`", "", line)):
                if re.match(r"^[a-z][a-z0-9+.-]*:", target):  # http:, https:, mailto:
                    continue
                file_part, _, fragment = target.partition("#")
                where = os.path.normpath(os.path.join(os.path.dirname(path), file_part)) \
                    if file_part else path
                why = None
                if not os.path.realpath(where).startswith(os.path.realpath(repo) + os.sep):
                    why = "points outside the repository"
                elif not os.path.exists(where):
                    why = "no such file"
                elif fragment and where.endswith(".md") and fragment not in anchors(where):
                    why = "no heading with the anchor #%s in %s" % (
                        fragment, os.path.relpath(where, repo))
                if why:
                    problems.append("%s:%d: %s: %s" % (rel, number, target, why))
    return problems


def main():
    repo = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else
                           os.path.join(os.path.dirname(__file__), ".."))
    problems = check(repo)
    for p in problems:
        print(p)
    count = sum(1 for _ in markdown_files(repo))
    print("doc links: %d Markdown files checked, %d broken link(s)" % (count, len(problems)))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
