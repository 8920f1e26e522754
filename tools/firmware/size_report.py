#!/usr/bin/env python3
"""Code size of the splintcore core per module (src/<module>), for the bare-metal CI job.

Two views, both in bytes as arm-none-eabi-size counts them (text = code + read-only data):
  archive  every object of libsplintcore.a (built with -ffunction-sections -fdata-sections),
           i.e. what a firmware that used every function would link;
  linked   what the firmware example's image really holds from each module after
           --gc-sections, read from the linker map (input sections attributed to
           libsplintcore.a(<object>)).
usage: size_report.py SIZE_TOOL OBJECT_DIR MAP_FILE
  OBJECT_DIR: .../CMakeFiles/splintcore.dir (objects under src/<module>/)
"""
import os
import re
import subprocess
import sys


def main():
    size_tool, object_dir, map_file = sys.argv[1:4]
    src = os.path.join(object_dir, "src")
    module_of = {}      # object basename -> module
    archive = {}        # module -> [text, data, bss]
    objects = []
    for module in sorted(os.listdir(src)):
        for name in sorted(os.listdir(os.path.join(src, module))):
            if name.endswith((".obj", ".o")):
                objects.append((module, os.path.join(src, module, name)))
                module_of[name] = module if name not in module_of else "?"
    out = subprocess.run([size_tool, "-B"] + [p for _, p in objects], check=True,
                         capture_output=True, text=True).stdout.splitlines()[1:]
    for (module, _), line in zip(objects, out):
        text, data, bss = (int(x) for x in line.split()[:3])
        a = archive.setdefault(module, [0, 0, 0])
        a[0] += text
        a[1] += data
        a[2] += bss

    linked = {m: [0, 0, 0] for m in archive}
    other = [0, 0, 0]
    # Input sections in the map: " .text.name 0xADDR 0xSIZE file" (name and the rest may be
    # on two lines when the name is long). Only the part before the discarded-sections list
    # and the memory map counts: read from "Linker script and memory map".
    text = open(map_file, encoding="utf-8", errors="replace").read()
    start = text.find("Linker script and memory map")
    body = text[start:] if start >= 0 else text
    pattern = re.compile(
        r"^ (\.[A-Za-z_][\w.$]*)\s*\n?\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S+)\s*$", re.M)
    for section, _addr, size, origin in pattern.findall(body):
        n = int(size, 16)
        if n == 0:
            continue
        if section.startswith((".text", ".rodata", ".ARM")):
            kind = 0
        elif section.startswith((".data", ".got")):
            kind = 1
        elif section.startswith((".bss", "COMMON")):
            kind = 2
        else:
            continue
        m = re.search(r"libsplintcore\.a\(([^)]+)\)", origin)
        if m and m.group(1) in module_of:
            linked.setdefault(module_of[m.group(1)], [0, 0, 0])[kind] += n
        else:
            other[kind] += n

    print("%-10s %9s %7s %7s   %9s %7s %7s" % ("module", "text", "data", "bss",
                                                "linked", "data", "bss"))
    totals = [0] * 6
    for module in sorted(archive):
        a, l = archive[module], linked.get(module, [0, 0, 0])
        print("%-10s %9d %7d %7d   %9d %7d %7d" % ((module,) + tuple(a) + tuple(l)))
        for i, v in enumerate(a + l):
            totals[i] += v
    print("%-10s %9d %7d %7d   %9d %7d %7d" % (("all",) + tuple(totals)))
    print("%-10s %9s %7s %7s   %9d %7d %7d  (example, start-up, embedded inputs, libc, libm,"
          " libgcc, libstdc++ number conversion)" % (("other", "", "", "") + tuple(other)))
    print("linked core text %d" % totals[3])


if __name__ == "__main__":
    main()
