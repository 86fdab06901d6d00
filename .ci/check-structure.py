#!/usr/bin/env python3
"""Structure checks of the library (issue 13), run by CI:

1. no function in `src/` longer than 150 lines (but for one marked `// long-fn: <reason>`:
   parsers may say why they need more);
2. no `too_many_arguments` allow in `src/`;
3. no two files of the library that import each other (a `use` of the other file's items, or
   a path into it, both ways), between modules that are not parent and child: a module's root
   file declares its children and they use its types, which Rust's module tree asks for.

Exits non-zero, listing what fails.
"""
import os
import re
import sys

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
SRC = os.path.join(ROOT, "src")
MAX_LINES = 150

failures = []


def rust_files():
    for d, _, files in os.walk(SRC):
        for f in sorted(files):
            if f.endswith(".rs"):
                yield os.path.join(d, f)


def strip(line):
    """A line without its `//` comment and string contents (good enough for braces)."""
    line = re.sub(r'"(\\.|[^"\\])*"', '""', line)
    line = re.sub(r"'(\\.|[^'\\])'", "''", line)
    i = line.find("//")
    return line if i < 0 else line[:i]


FN = re.compile(r"^\s*(pub(\([a-z]+\))?\s+)?(const\s+)?(unsafe\s+)?fn\s+(\w+)")

for path in rust_files():
    lines = open(path, encoding="utf-8").read().split("\n")
    rel = os.path.relpath(path, ROOT)
    for k, line in enumerate(lines):
        if "too_many_arguments" in line:
            failures.append(f"{rel}:{k + 1}: a too_many_arguments allow")
        m = FN.match(line)
        if not m:
            continue
        # `// long-fn: <reason>` just above a function (parsers may need more lines) exempts it.
        above = k - 1
        while above >= 0 and re.match(r"^\s*(///|#\[)", lines[above]):
            above -= 1
        comment = []
        while above >= 0 and lines[above].strip().startswith("//"):
            comment.append(lines[above])
            above -= 1
        if any("long-fn:" in c for c in comment):
            continue
        depth, opened = 0, False
        for j in range(k, len(lines)):
            s = strip(lines[j])
            if not opened and ";" in s and "{" not in s:
                break  # a declaration without a body
            depth += s.count("{") - s.count("}")
            opened |= "{" in s
            if opened and depth <= 0:
                length = j - k + 1
                if length > MAX_LINES:
                    failures.append(f"{rel}:{k + 1}: fn {m.group(5)} is {length} lines")
                break

# --- imports between files
# Module of each file, as a tuple of names under `src/shared` (the tree mounted per dimension).
SHARED = os.path.join(SRC, "shared")


def module_of(path):
    rel = os.path.relpath(path, SHARED)[:-3].split(os.sep)
    if rel[-1] == "mod":
        rel = rel[:-1]
    return tuple(rel)


files = {module_of(p): p for p in rust_files() if p.startswith(SHARED + os.sep)}
# `#[path = "rerun.rs"] mod recorder;`
if ("rerun",) in files:
    files[("recorder",)] = files.pop(("rerun",))


def resolve(module, path):
    """The file a `super::…` path from `module` lands in (the longest module prefix)."""
    parts = path.split("::")
    base = list(module)
    while parts and parts[0] == "super":
        parts.pop(0)
        base = base[:-1]
    target = tuple(base)
    best = target if target in files else None
    for p in parts:
        target = target + (p,)
        if target in files:
            best = target
        else:
            break
    return best


USE = re.compile(r"\b((?:super::)+[\w:]*(?:\{[^;]*?\})?)", re.S)
edges = {}
for module, path in files.items():
    text = "\n".join(strip(l) for l in open(path, encoding="utf-8").read().split("\n"))
    out = set()
    for m in USE.finditer(text):
        p = m.group(1)
        head, _, group = p.partition("{")
        names = [n.strip() for n in re.split(r"[,{}]", group)] if group else [""]
        for n in names:
            full = (head + n).rstrip(":").split(" as ")[0]
            t = resolve(module, full)
            if t is not None and t != module:
                out.add(t)
    edges[module] = out


def parent_child(a, b):
    return a[:-1] == b or b[:-1] == a


for a, outs in edges.items():
    for b in outs:
        if a < b and a in edges.get(b, ()) and not parent_child(a, b):
            failures.append(
                f"{os.path.relpath(files[a], ROOT)} and {os.path.relpath(files[b], ROOT)} "
                "import each other"
            )

for f in failures:
    print(f)
if failures:
    sys.exit(1)
print(f"structure: {len(files)} library files; functions ≤ {MAX_LINES} lines, no "
      "too_many_arguments allow, no two files importing each other")
