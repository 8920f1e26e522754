#!/usr/bin/env python3
"""The command table, `--help` and the README agree (issue 27, one CLI).

usage: cli_commands.py PATH/TO/splintcore README.md
Checks: the commands `splintcore --help` lists (from the table in tools/splintcore/main.cpp)
are exactly those the README's "The program" section shows, in the same order; each command's
`--help` exits 0, starts with "usage: splintcore NAME" and ends with its options as the
command's option table lists them ("options:", one "  --name" line each); every option that
the usage text above that list names, every option the README shows for the command, and
every option `splintcore --help` gives as an option of every command is in that list.
Prints one line per problem; exit 1 on any.
"""
import re
import subprocess
import sys


def main():
    tool, readme = sys.argv[1], sys.argv[2]
    problems = []
    out = subprocess.run([tool, "--help"], capture_output=True, text=True)
    if out.returncode != 0:
        problems.append("splintcore --help exits %d" % out.returncode)
    listed = []
    in_commands = False
    for line in out.stdout.splitlines():
        if line == "commands:":
            in_commands = True
        elif in_commands and not line.strip():
            break
        elif in_commands:
            listed.append(line.split()[0])
    every = out.stdout.partition("\noptions of every command:\n")[2].partition("\n\n")[0]
    common = re.findall(r"^  (-[-a-z0-9]+)", every, re.M)
    if not common:
        problems.append("splintcore --help lists no options of every command")
    # The README's program block: "    splintcore NAME ..." and its continuation lines.
    text = open(readme, encoding="utf-8").read()
    section = text[text.index("## The program"):]
    section = section[:section.index("\n## ", 3)] if "\n## " in section[3:] else section
    shown = {}
    order = []
    current = None
    for line in section.splitlines():
        m = re.match(r"^    splintcore ([a-z-]+)(.*)$", line)
        if m:
            current = m.group(1)
            order.append(current)
            shown[current] = m.group(2)
        elif current and line.startswith("     ") and line.strip():
            shown[current] += " " + line.strip()
        elif not line.startswith("    "):
            current = None
    if listed != order:
        problems.append("commands in --help %s differ from the README's %s" % (listed, order))
    for name in listed:
        h = subprocess.run([tool, name, "--help"], capture_output=True, text=True)
        if h.returncode != 0:
            problems.append("splintcore %s --help exits %d" % (name, h.returncode))
        if not h.stdout.startswith("usage: splintcore " + name):
            problems.append("splintcore %s --help does not start with its usage line" % name)
        usage, _, options = h.stdout.partition("\noptions:\n")
        table = set(re.findall(r"^  (-[-a-z0-9]+)", options, re.M))
        if not table:
            problems.append("splintcore %s --help lists no options" % name)
        for option in sorted(set(re.findall(r"--[a-z][a-z0-9-]*", usage))):
            if option not in table:
                problems.append("splintcore %s --help names %s, its options do not" % (name, option))
        for option in sorted(set(re.findall(r"--[a-z][a-z0-9-]*", shown.get(name, "")))):
            if option not in table:
                problems.append("the README shows %s for %s, its options do not" % (option, name))
        for option in common:
            if option not in table:
                problems.append("%s is an option of every command, not of %s" % (option, name))
    for p in problems:
        print("cli_commands: " + p)
    print("cli_commands: %d commands, %d problem(s)" % (len(listed), len(problems)))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
