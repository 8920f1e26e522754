#!/usr/bin/env python3
"""Function lengths in src/, measured as STYLE.md measures the model codebases (issue 27).

Universal Ctags gives every function's first and last line (lambdas excluded: they are
counted in the function that holds them); a function's length is end - start + 1. Prints:
  - the functions over --list lines (default 150), longest first;
  - the figures: function count, over 100, over 150, over 200, and the share of function
    lines that sit in functions over 100 lines.
With --check, exits 1 when a function is over --max lines (default 150) that
tools/function_sizes.allow does not list with at least its length (the ratchet: a listed
function may shrink, never grow, and no new one may pass the limit), or when the share of
lines in functions over 100 lines exceeds --max-share (percent).
usage: tools/function_sizes.py [--check] [--max N] [--max-share P] [--list N] [DIR...]
"""
import argparse
import os
import re
import subprocess
import sys


def functions(paths):
    out = subprocess.run(["ctags", "-R", "--languages=C++", "--c++-kinds=f", "--fields=+ne",
                          "--extras=-q", "-o", "-"] + paths,
                         check=True, capture_output=True, text=True).stdout
    seen = set()
    for line in out.splitlines():
        parts = line.split("\t")
        name, path = parts[0], parts[1]
        if name.startswith("__anon"):
            continue  # a lambda: part of its enclosing function
        fields = dict(p.split(":", 1) for p in parts[3:] if ":" in p)
        if "line" not in fields or "end" not in fields:
            continue
        start, end = int(fields["line"]), int(fields["end"])
        scope = fields.get("class") or fields.get("struct") or fields.get("namespace") or ""
        key = (path, start)
        if key in seen:
            continue
        seen.add(key)
        # Anonymous namespaces get a generated name (__anonHEX): left out, so names stay put.
        full = re.sub(r"__anon[0-9a-f]+::", "", (scope + "::" if scope else "") + name)
        yield path, start, end - start + 1, full


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--check", action="store_true")
    ap.add_argument("--max", type=int, default=150)
    ap.add_argument("--max-share", type=float, default=None)
    ap.add_argument("--list", type=int, default=150)
    ap.add_argument("dirs", nargs="*", default=["src"])
    a = ap.parse_args()
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    os.chdir(root)
    fs = sorted(functions(a.dirs), key=lambda f: (-f[2], f[0], f[1]))
    total = sum(f[2] for f in fs)
    over = lambda n: [f for f in fs if f[2] > n]
    share = 100.0 * sum(f[2] for f in over(100)) / total if total else 0.0
    for path, start, length, name in over(a.list):
        print(f"{length:5d}  {path}:{start}  {name}")
    print(f"functions {len(fs)}, lines in functions {total}; over 100 lines: {len(over(100))}, "
          f"over 150: {len(over(150))}, over 200: {len(over(200))}; "
          f"share of function lines in functions over 100 lines: {share:.1f}%")
    if not a.check:
        return 0
    allow = {}
    allow_path = "tools/function_sizes.allow"
    if os.path.exists(allow_path):
        for line in open(allow_path, encoding="utf-8"):
            line = line.split("#", 1)[0].strip()
            if line:
                length, path, name = line.split(None, 2)
                allow[(path, name)] = int(length)
    bad = []
    for path, start, length, name in over(a.max):
        limit = allow.get((path, name))
        if limit is None:
            bad.append(f"{path}:{start}: {name} has {length} lines (limit {a.max})")
        elif length > limit:
            bad.append(f"{path}:{start}: {name} grew to {length} lines (allowed {limit}: shrink it)")
    if a.max_share is not None and share > a.max_share:
        bad.append(f"{share:.1f}% of function lines are in functions over 100 lines "
                   f"(limit {a.max_share}%)")
    for b in bad:
        print("function_sizes: " + b)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
