#!/usr/bin/env python3
"""One catalog of invariant ids (docs/invariants.md) for both fail-safe checkers: the C++
deterministic simulation (src/simulation/failsafe_simulation.cpp, simInvariants()) and the
Python scenario model (test/scenarios/machine.py, model.py). Checks that

- every id in the catalog is unique, and names its checker (simulation and/or scenarios);
- every id in simInvariants() is in the catalog with "simulation", and every catalog id with
  "simulation" is in simInvariants(); the rules its docs string cites are the catalog row's;
- every id the scenario test fails with (fail("I13", ...), invariant = "I13", or an expectation
  whose reason starts with an id, "I13 (...)") is in the catalog with "scenarios", and every
  catalog id with "scenarios" is used there;
- every rule id (F12) the catalog or simInvariants() cites is a rule of docs/failsafe.md, and
  every rule id defined there (a list item starting **F12**) is defined once, and every rule id
  failsafe.md cites in its own text exists.

Prints each problem and exits 1; prints one summary line and exits 0 when there is none.

Usage: check_invariants.py [--repo DIR] [--catalog F] [--failsafe F] [--cpp F] [--python F ...]
                           [--junit OUT.xml]
  (paths default to the repository's files; --junit also writes one JUnit case,
  invariants_one_catalog, with scripts/junit.py's writer)"""
import argparse
import os
import re
import sys

ID = r"(?:I|L)\d+"
RULE_DEF = re.compile(r"^\s*[-*]\s+\*\*(F\d+)\*\*")
RULE_REF = re.compile(r"\bF(\d+)(?:\s*-\s*F?(\d+))?\b")
CPP_ENTRY = re.compile(r'\{\s*"([^"]+)"\s*,\s*"((?:[^"\\]|\\.)*)"')
PY_FAIL = re.compile(r'\bfail\(\s*"([^"]*)"')
PY_ASSIGN = re.compile(r'\binvariant\s*=\s*"([^"]*)"')
PY_WHY = re.compile(r'"(%s) \(' % ID)
CHECKERS = ("simulation", "scenarios")


def rule_ids(text):
    """Every rule id a text cites; F3-F5 (or F3-5) stands for F3, F4, F5."""
    out = []
    for m in RULE_REF.finditer(text):
        lo = int(m.group(1))
        hi = int(m.group(2)) if m.group(2) else lo
        out += ["F%d" % n for n in range(lo, max(lo, hi) + 1)]
    return out


def read(path, problems):
    try:
        with open(path, encoding="utf-8") as f:
            return f.read()
    except OSError as e:
        problems.append("%s: cannot read: %s" % (path, e))
        return ""


def failsafe_rules(path, problems):
    """The rules docs/failsafe.md defines, each once, outside code blocks."""
    defined, fenced = {}, False
    text = read(path, problems)
    for n, line in enumerate(text.splitlines(), 1):
        if line.lstrip().startswith("```"):
            fenced = not fenced
            continue
        m = None if fenced else RULE_DEF.match(line)
        if not m:
            continue
        if m.group(1) in defined:
            problems.append("%s:%d: rule %s defined again (first at line %d)"
                            % (path, n, m.group(1), defined[m.group(1)]))
        else:
            defined[m.group(1)] = n
    if not defined:
        problems.append("%s: no rules (list items starting **F1**, **F2**, ...)" % path)
    for n, line in enumerate(text.splitlines(), 1):
        for r in rule_ids(line):
            if r not in defined:
                problems.append("%s:%d: cites rule %s, which it does not define" % (path, n, r))
    return defined


def catalog(path, problems):
    """{id: (line, rules, checkers)} from the table whose header starts `| id |`."""
    rows, in_table = {}, False
    for n, line in enumerate(read(path, problems).splitlines(), 1):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if line.startswith("|") and cells[0] == "id" and len(cells) >= 4:
            in_table = True
            continue
        if not in_table:
            continue
        if not line.startswith("|"):
            break
        if set(cells[0]) <= set("-: "):
            continue
        if len(cells) < 4 or not re.fullmatch(ID, cells[0]):
            problems.append("%s:%d: not a catalog row (id | what | rules | checked by): %s"
                            % (path, n, line.strip()))
            continue
        cid, rules, checked = cells[0], cells[2], cells[3]
        if cid in rows:
            problems.append("%s:%d: id %s is in the catalog twice (first at line %d)"
                            % (path, n, cid, rows[cid][0]))
            continue
        checkers = {c for c in CHECKERS if c in checked}
        if not checkers:
            problems.append("%s:%d: %s names no checker (simulation, scenarios): %r"
                            % (path, n, cid, checked))
        rows[cid] = (n, rule_ids(rules), checkers)
    if not rows:
        problems.append("%s: no catalog table (| id | what it asserts | rules | checked by |)"
                        % path)
    return rows


def cpp_table(path, problems):
    """{id: docs string} of simInvariants()'s entries."""
    text = read(path, problems)
    start = text.find("simInvariants()")
    end = text.find("return list;", start)
    if start < 0 or end < 0:
        problems.append("%s: no simInvariants() table" % path)
        return {}
    entries = {}
    for m in CPP_ENTRY.finditer(text, start, end):
        line = text.count("\n", 0, m.start()) + 1
        if m.group(1) in entries:
            problems.append("%s:%d: %s is in simInvariants() twice" % (path, line, m.group(1)))
        entries[m.group(1)] = (line, m.group(2))
    return entries


def python_ids(paths, problems):
    """{id: [where]} of every id the scenario test fails with."""
    used = {}
    for path in paths:
        for n, line in enumerate(read(path, problems).splitlines(), 1):
            for pattern in (PY_FAIL, PY_ASSIGN, PY_WHY):
                for m in pattern.finditer(line):
                    used.setdefault(m.group(1), []).append("%s:%d" % (path, n))
    return used


def check(args):
    problems = []
    rules = failsafe_rules(args.failsafe, problems)
    rows = catalog(args.catalog, problems)
    for cid, (n, cited, _) in sorted(rows.items()):
        for r in cited:
            if r not in rules:
                problems.append("%s:%d: %s cites rule %s, which %s does not define"
                                % (args.catalog, n, cid, r, args.failsafe))
    cpp = cpp_table(args.cpp, problems)
    for cid, (n, docs) in sorted(cpp.items()):
        where = "%s:%d" % (args.cpp, n)
        if cid not in rows:
            problems.append("%s: simInvariants() has %s, the catalog %s does not"
                            % (where, cid, args.catalog))
            continue
        if "simulation" not in rows[cid][2]:
            problems.append("%s: simInvariants() checks %s, the catalog does not name simulation"
                            % (where, cid))
        if re.search(r"failsafe\.md:\d", docs):
            problems.append("%s: %s cites failsafe.md by line number (%s): cite rule ids"
                            % (where, cid, docs))
        for r in rule_ids(docs):
            if r not in rules:
                problems.append("%s: %s cites rule %s, which %s does not define"
                                % (where, cid, r, args.failsafe))
            elif r not in rows[cid][1]:
                problems.append("%s: %s cites rule %s, the catalog's row does not"
                                % (where, cid, r))
    py = python_ids(args.python, problems)
    for cid, places in sorted(py.items()):
        if cid not in rows:
            problems.append("%s: the scenario test fails with %r, the catalog %s has no such id"
                            % (places[0], cid, args.catalog))
        elif "scenarios" not in rows[cid][2]:
            problems.append("%s: the scenario test uses %s, the catalog does not name scenarios"
                            % (places[0], cid))
    for cid, (n, _, checkers) in sorted(rows.items()):
        if "simulation" in checkers and cid not in cpp:
            problems.append("%s:%d: %s names simulation, simInvariants() has no %s"
                            % (args.catalog, n, cid, cid))
        if "scenarios" in checkers and cid not in py:
            problems.append("%s:%d: %s names scenarios, the scenario test never uses it"
                            % (args.catalog, n, cid))
    return problems, "%d invariants (%d in the simulation, %d in the scenario test), %d rules" % (
        len(rows), len(cpp), len(py), len(rules))


def main():
    repo_default = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--repo", default=repo_default)
    p.add_argument("--catalog")
    p.add_argument("--failsafe")
    p.add_argument("--cpp")
    p.add_argument("--python", nargs="+")
    p.add_argument("--junit")
    args = p.parse_args()
    args.catalog = args.catalog or os.path.join(args.repo, "docs", "invariants.md")
    args.failsafe = args.failsafe or os.path.join(args.repo, "docs", "failsafe.md")
    args.cpp = args.cpp or os.path.join(args.repo, "src", "simulation", "failsafe_simulation.cpp")
    args.python = args.python or [os.path.join(args.repo, "test", "scenarios", f)
                                  for f in ("machine.py", "model.py")]
    problems, summary = check(args)
    for problem in problems:
        print(problem)
    print("invariants: %s: %s" % (summary, "%d problem(s)" % len(problems) if problems else "one catalog"))
    if args.junit:
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        from junit import write_suite
        os.makedirs(os.path.dirname(os.path.abspath(args.junit)), exist_ok=True)
        write_suite(args.junit, "conventions", [("invariants_one_catalog", "\n".join(problems), None)])
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
