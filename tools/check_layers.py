#!/usr/bin/env python3
"""The map of the library, checked (issue 27): every arrow points down.

docs/architecture.md holds the one table of modules and floors. This script reads it and
checks, for the tree as it is:
  - every public header include/splintcore/<name>.h has a row, and its module's folder
    src/<module>/ exists (a header is implemented in the folder of its name; the C API,
    splintcore.h, lives in src/capi/);
  - every folder of src/ has a row;
  - no file of a module includes a header of a module on the same or a higher floor: a public
    header "splintcore/<name>.h" or another module's private header "<module>/<file>.h"
    (includes inside the module itself are free).
Prints one line per violation and exits 1 when there is any; otherwise prints the floors.
usage: tools/check_layers.py [REPO_ROOT]
"""
import os
import re
import sys


def read_table(path):
    """Rows of the floors table: | floor | module | header | folder | ... |"""
    rows = {}
    in_table = False
    for line in open(path, encoding="utf-8"):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if line.startswith("| floor | module | header | folder"):
            in_table = True
            continue
        if not in_table:
            continue
        if not line.startswith("|"):
            break
        if set(cells[0]) <= set("-: "):
            continue
        floor, module, header, folder = cells[0], cells[1].strip("`"), cells[2].strip("`"), cells[3].strip("`")
        rows[module] = {"floor": int(floor), "header": header, "folder": folder.rstrip("/")}
    return rows


def includes(path):
    pattern = re.compile(r'^\s*#\s*include\s+"([^"]+)"')
    with open(path, encoding="utf-8", errors="replace") as f:
        for number, line in enumerate(f, 1):
            m = pattern.match(line)
            if m:
                yield number, m.group(1)


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..")
    os.chdir(root)
    rows = read_table("docs/architecture.md")
    problems = []
    if not rows:
        print("check_layers: no floors table in docs/architecture.md")
        return 1
    by_header = {r["header"]: m for m, r in rows.items() if r["header"] not in ("", "-")}
    by_folder = {r["folder"]: m for m, r in rows.items()}
    for name in sorted(os.listdir("include/splintcore")):
        if name.endswith(".h") and name not in by_header:
            problems.append(f"include/splintcore/{name}: no row in docs/architecture.md")
    for module, r in rows.items():
        if not os.path.isdir(r["folder"]):
            problems.append(f"{module}: folder {r['folder']}/ does not exist")
        if r["header"] not in ("", "-") and not os.path.isfile("include/splintcore/" + r["header"]):
            problems.append(f"{module}: header {r['header']} does not exist")
    for name in sorted(os.listdir("src")):
        if os.path.isdir(os.path.join("src", name)) and f"src/{name}" not in by_folder:
            problems.append(f"src/{name}/: no row in docs/architecture.md")

    def module_of_include(text):
        if text.startswith("splintcore/"):
            return by_header.get(text[len("splintcore/"):])
        first = text.split("/")[0]
        return by_folder.get(f"src/{first}")

    files = []
    for module, r in rows.items():
        folder = r["folder"]
        if os.path.isdir(folder):
            for dirpath, _, names in os.walk(folder):
                for n in sorted(names):
                    if n.endswith((".h", ".cpp", ".c")):
                        files.append((module, os.path.join(dirpath, n)))
        if r["header"] not in ("", "-"):
            files.append((module, "include/splintcore/" + r["header"]))
    for module, path in sorted(files):
        floor = rows[module]["floor"]
        for number, text in includes(path):
            dep = module_of_include(text)
            if dep is None or dep == module:
                continue
            if rows[dep]["floor"] >= floor:
                problems.append(f"{path}:{number}: {module} (floor {floor}) includes {text} of "
                                f"{dep} (floor {rows[dep]['floor']}): an arrow that does not point down")
    if problems:
        for p in problems:
            print("check_layers: " + p)
        print(f"check_layers: {len(problems)} problem(s)")
        return 1
    floors = {}
    for module, r in rows.items():
        floors.setdefault(r["floor"], []).append(module)
    for floor in sorted(floors):
        print(f"floor {floor}: {' '.join(sorted(floors[floor]))}")
    print(f"check_layers: {len(files)} files of {len(rows)} modules, every include points down")
    return 0


if __name__ == "__main__":
    sys.exit(main())
