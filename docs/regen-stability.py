#!/usr/bin/env python3
"""Re-runs every command block of docs/STABILITY.md and puts its output in the block below it.

    python3 docs/regen-stability.py            # all tables (about an hour: the 3D cantilever is 45 min)
    python3 docs/regen-stability.py crush limb # only the blocks whose command names a scene
    python3 docs/regen-stability.py --no-fem   # skip the rapier-FEM blocks (rapier alone)

A command block is a ```text block whose only line starts with `cargo run`; the ```text block
right after it holds the table that command prints (stdout). The prose around the tables is not
touched: read the new numbers and update it by hand.
"""

import pathlib
import re
import subprocess
import sys

DOC = pathlib.Path(__file__).resolve().parent / "STABILITY.md"
BLOCK = re.compile(r"```text\n(cargo run[^\n]*)\n```\n(\s*)```text\n(.*?)```", re.S)


def main() -> int:
    only = [a for a in sys.argv[1:] if not a.startswith("--")]
    no_fem = "--no-fem" in sys.argv[1:]
    text = DOC.read_text()
    out = []
    last = 0
    for m in BLOCK.finditer(text):
        command, gap, table = m.group(1), m.group(2), m.group(3)
        words = command.split()
        scene = words[words.index("--") + 1] if "--" in words else ""
        if (only and scene not in only) or (no_fem and any(w.split("/")[-1] == "fem" for w in words)):
            continue
        print(f"== {command}", file=sys.stderr, flush=True)
        run = subprocess.run(command, shell=True, capture_output=True, text=True,
                             cwd=DOC.parent.parent)
        if run.returncode != 0:
            sys.stderr.write(run.stderr)
            print(f"failed: {command}", file=sys.stderr)
            return 1
        out.append(text[last:m.start(3)])
        out.append(run.stdout if run.stdout.endswith("\n") else run.stdout + "\n")
        last = m.end(3)
    out.append(text[last:])
    DOC.write_text("".join(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
