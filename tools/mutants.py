#!/usr/bin/env python3
"""Mutation testing of one source file: do the tests fail when its logic changes?

Each mutant changes one operator at one place in FILE's lines FIRST..LAST (a comparison made
strict or not, == and != swapped, && and || swapped, a + 1 or - 1 dropped, a ++counter;
statement removed), rebuilds the unit-test binary and runs the tests FILTER selects. A mutant
the tests pass ("survived") is a change of behaviour no test notices, unless it is equivalent
(the same behaviour by another route): each survivor is a line to read. With --wider, a
survivor is run again against a wider filter (timeouts: 20 s for FILTER, 600 s for --wider; a
timeout counts as killed). A mutant that does not compile (the warnings are errors) is
"nobuild".

Run it in a clone of the tree with its own build (it rewrites FILE in place, and puts it back
at the end, on an error and on SIGINT/SIGTERM), e.g.:
  git clone -q . /tmp/mut && cmake -S /tmp/mut -B /tmp/mut/build/rel -G Ninja \\
      -DCMAKE_BUILD_TYPE=Release && ninja -C /tmp/mut/build/rel splintcore_tests
  python3 tools/mutants.py --tree /tmp/mut src/mesh/check.cpp 95 600 \\
      'CheckMesh.*:SmallShells.*' --wider '*Check*:*Mesh*:*Exhaust*'
Not part of CI: a file of 500 lines makes 150-200 mutants, about 10 s each. --build DIR takes
another Ninja build of the tree, e.g. one with -DSPLINTCORE_SANITIZE=ON: there the arena
poisons the gap before each allocation, so a mutant that writes one element past an arena
array into a gap fails too (slower: each rebuild and run is under ASan).
"""
import argparse
import os
import re
import signal
import subprocess
import sys

OPERATORS = [(" < ", " <= "), (" <= ", " < "), (" > ", " >= "), (" >= ", " > "),
             (" == ", " != "), (" != ", " == "), (" && ", " || "), (" || ", " && "),
             (" + 1", " + 0"), (" - 1", " - 0")]
INCREMENT = re.compile(r"^(\s*)(\+\+[\w\->\[\]\.]+;)")


def mutants(lines, first, last):
    """(line index, column, old text, new text) for every site in lines first..last."""
    found = []
    for i in range(first - 1, min(last, len(lines))):
        code = lines[i].split("//")[0]
        if not code.strip() or code.strip().startswith("#"):
            continue
        for old, new in OPERATORS:
            for m in re.finditer(re.escape(old), code):
                found.append((i, m.start(), old, new))
        m = INCREMENT.match(code)
        if m:
            found.append((i, len(m.group(1)), m.group(2), ";"))
    return found


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("file")
    ap.add_argument("first", type=int)
    ap.add_argument("last", type=int)
    ap.add_argument("filter")
    ap.add_argument("--wider", default=None)
    ap.add_argument("--tree", default=".")
    ap.add_argument("--build", default="build/rel")
    a = ap.parse_args()
    path = os.path.join(a.tree, a.file)
    original = open(path).read()
    lines = original.split("\n")

    # A signal ends the run through the `finally` below, which puts the file back.
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(1))
    signal.signal(signal.SIGINT, lambda *_: sys.exit(1))

    def run(test_filter, limit):
        if subprocess.run(["ninja", "-C", a.build, "splintcore_tests"], cwd=a.tree,
                          capture_output=True).returncode != 0:
            return "nobuild"
        r = subprocess.run(["timeout", limit, os.path.join(a.build, "tests/splintcore_tests"),
                            "--gtest_filter=" + test_filter], cwd=a.tree, capture_output=True)
        return "killed" if r.returncode != 0 else "survived"

    found = mutants(lines, a.first, a.last)
    print("%d mutants of %s:%d-%d" % (len(found), a.file, a.first, a.last), flush=True)
    counts = {}
    try:
        for i, col, old, new in found:
            changed = list(lines)
            changed[i] = changed[i][:col] + new + changed[i][col + len(old):]
            with open(path, "w") as f:
                f.write("\n".join(changed))
            result = run(a.filter, "20")
            if result == "survived" and a.wider:
                result = "killed (wider)" if run(a.wider, "600") == "killed" else "survived"
            counts[result] = counts.get(result, 0) + 1
            print("%s %d:%d %r -> %r | %s" % (result, i + 1, col, old, new,
                                             lines[i].strip()[:100]), flush=True)
    finally:
        with open(path, "w") as f:
            f.write(original)
        subprocess.run(["ninja", "-C", a.build, "splintcore_tests"], cwd=a.tree,
                       capture_output=True)
    print(", ".join("%s %d" % kv for kv in sorted(counts.items())))


if __name__ == "__main__":
    main()
