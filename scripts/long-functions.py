#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Functions longer than a limit (80 lines by default) outside tests/ (docs/architecture.md).

Rough on purpose: a function starts at a line that looks like a signature (`type name(`, not a
control statement, a lambda or an assignment), at any indentation (methods in a class body
count too), and ends at the next `}` at the same indentation. A lambda counts with the function
it is in. Prints `lines path:line name`, longest first; exit code 1 if any.
"""
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SKIP_TOP = {"tests", "build", "docs", "cmake", "config"}
SIGNATURE = re.compile(r"^(\s*)(?!#|//|\}|\*)((?:[\w:<>,\*&~]+\s+)*?[\w:<>\*&~]*?\b([~\w:]+|operator\S+))\s*\(")
NOT_FUNCTIONS = {"if", "for", "while", "switch", "catch", "return", "else", "do", "case", "sizeof",
                 "static_assert", "co_return", "throw", "new", "delete", "decltype", "alignas",
                 "namespace", "struct", "class", "enum", "union", "using", "typedef", "defined"}


def signature(line):
    line = re.sub(r"\[\[[^\]]*\]\]\s*", "", line)  # attributes
    m = SIGNATURE.match(line)
    if not m:
        return None
    head = line[:line.index("(")]
    first = head.split()[0] if head.split() else ""
    if first in NOT_FUNCTIONS or m.group(3) in NOT_FUNCTIONS or "=" in head or "[" in line:
        return None
    if "." in head or "->" in head:
        return None
    if len(head.split()) < 2 and (m.group(1) or "::" not in head):
        return None  # a call statement; a constructor counts only when defined at column 0
    return m.group(1), m.group(3)


def long_functions(path, limit):
    with open(path, encoding="utf-8", errors="replace") as fh:
        lines = fh.read().split("\n")
    out, i = [], 0
    while i < len(lines):
        sig = signature(lines[i])
        before = lines[i - 1].strip() if i else ""
        if sig and before and not before.startswith(("//", "#", "*", "/*")) \
                and not before.endswith((";", "{", "}", ":", ">", "]]", "*/")):
            sig = None  # the continuation of a statement, not a signature
        if not sig:
            i += 1
            continue
            i += 1
            continue
        indent, name = sig
        # the signature runs until a line that opens the body, or ends with ';' (a declaration)
        j = i
        while j < len(lines) and "{" not in lines[j] and not lines[j].rstrip().endswith(";") \
                and j - i < 12:
            j += 1
        if j >= len(lines) or not lines[j].rstrip().endswith("{"):
            i += 1
            continue
        k = j + 1
        while k < len(lines) and not (lines[k].startswith(indent + "}")
                                      and not lines[k].startswith(indent + " ")):
            k += 1
        length = k - i + 1
        if length > limit:
            out.append((length, i + 1, name))
        i = k + 1 if length > limit else j + 1
    return out


def main():
    limit = int(sys.argv[1]) if len(sys.argv) > 1 else 80
    found = []
    for dirpath, dirnames, filenames in os.walk(ROOT):
        rel = os.path.relpath(dirpath, ROOT)
        dirnames[:] = [d for d in dirnames if not d.startswith(".") and not d.startswith("build")
                       and not (rel == "." and d in SKIP_TOP)]
        for name in filenames:
            if name.endswith((".cpp", ".hpp", ".c", ".h", ".cc")):
                path = os.path.join(dirpath, name)
                for length, line, fn in long_functions(path, limit):
                    found.append((length, os.path.relpath(path, ROOT), line, fn))
    for length, path, line, fn in sorted(found, reverse=True):
        print(f"{length:4d} {path}:{line} {fn}")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
