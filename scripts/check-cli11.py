#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""CLI11 stays in apps/common/src/command_line.cpp (ctest cli11_stays_in_command_line_cpp).

CLI11 2.x (Debian's) is header-only: every translation unit that includes <CLI/CLI.hpp> compiles
its validators, formatter and parser again, about 10 CPU-seconds each at -O3 and more under the
sanitizers (docs/build-times.md). Programs add their options through CommandLine::add_option and
the verbs of sim::apps::Option (sim/apps/command_line.hpp), which forward-declares CLI::App, so
only command_line.cpp compiles CLI11: no program does, the benchmarks (bench/) included. Exit
code 1, with each offending file and line, when another file includes CLI11.

  scripts/check-cli11.py [ROOT]     default: the repository this script is in
"""
import os
import re
import sys

ROOT = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SOURCES = (".hpp", ".h", ".hh", ".ipp", ".inl", ".cpp", ".cc", ".cxx", ".c")
CLI11 = re.compile(r'^\s*#\s*include\s*[<"]CLI/', re.M)
ALLOWED = {os.path.join("apps", "common", "src", "command_line.cpp")}


def sources(root):
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames[:] = sorted(d for d in dirnames if not d.startswith(".") and not d.startswith("build")
                             and d != "node_modules")
        for name in sorted(filenames):
            if name.endswith(SOURCES):
                yield os.path.join(dirpath, name)


def main():
    offenders = []
    checked = 0
    for path in sources(ROOT):
        relative = os.path.relpath(path, ROOT)
        if relative in ALLOWED:
            continue
        checked += 1
        with open(path, encoding="utf-8", errors="replace") as f:
            text = f.read()
        for match in CLI11.finditer(text):
            line = text.count("\n", 0, match.start()) + 1
            offenders.append(f"{relative}:{line}")
    if offenders:
        for where in offenders:
            print(f"{where}: includes CLI11 (about 10 CPU-seconds a compile); add the options through "
                  "CommandLine::add_option and sim::apps::Option's verbs (sim/apps/command_line.hpp), or "
                  "give CommandLine the verb that is missing, so CLI11 stays in apps/common/src/command_line.cpp")
        return 1
    print(f"check-cli11: none of {checked} other source files includes CLI11")
    return 0


if __name__ == "__main__":
    sys.exit(main())
