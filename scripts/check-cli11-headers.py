#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""CLI11 stays out of every header (ctest cli11_stays_out_of_headers).

CLI11 2.x (Debian's) is header-only: every translation unit that includes <CLI/CLI.hpp> compiles
its validators, formatter and parser again, about 10 CPU-seconds each at -O3 and more under the
sanitizers (docs/build-times.md). Headers forward-declare CLI::App (sim/apps/command_line.hpp);
only the .cpp files that add options include CLI11, so decoders, streams and their tests never
compile it. Exit code 1, with each offending header and line, when a header includes CLI11.

  scripts/check-cli11-headers.py [ROOT]     default: the repository this script is in
"""
import os
import re
import sys

ROOT = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
HEADERS = (".hpp", ".h", ".hh", ".ipp", ".inl")
CLI11 = re.compile(r'^\s*#\s*include\s*[<"]CLI/', re.M)


def headers(root):
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames[:] = sorted(d for d in dirnames if not d.startswith(".") and not d.startswith("build"))
        for name in sorted(filenames):
            if name.endswith(HEADERS):
                yield os.path.join(dirpath, name)


def main():
    offenders = []
    checked = 0
    for path in headers(ROOT):
        checked += 1
        with open(path, encoding="utf-8", errors="replace") as f:
            text = f.read()
        for match in CLI11.finditer(text):
            line = text.count("\n", 0, match.start()) + 1
            offenders.append(f"{os.path.relpath(path, ROOT)}:{line}")
    if offenders:
        for where in offenders:
            print(f"{where}: a header includes CLI11; forward-declare CLI::App (sim/apps/command_line.hpp) "
                  "and include <CLI/CLI.hpp> in the .cpp that adds the options")
        return 1
    print(f"check-cli11-headers: none of {checked} headers includes CLI11")
    return 0


if __name__ == "__main__":
    sys.exit(main())
