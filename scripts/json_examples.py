#!/usr/bin/env python3
"""Refreshes the example objects of docs/json.md from the real output of `bistable`.

Usage: scripts/json_examples.py [BISTABLE] [DOC]  (defaults: target/release/bistable, docs/json.md)

Each ```sh block of DOC that holds one `bistable ... --json` line (or `bistable classify ...`)
and is followed by a ```json block is run in one scratch directory, in the order of the file
(so a later command may read what an earlier one wrote), and the json block is replaced with
its output: floats rounded to 6 significant digits, arrays of more than 3 elements shortened to
the first element of each shape (at least 2). crates/bistable-cli/tests/json_docs.rs checks
that the real output has the keys and value types of these examples.
"""

import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

BLOCK = re.compile(r"```sh\n(bistable [^\n]*)\n```\n```json\n.*?\n```", re.S)


def shape(v):
    """The keys and value types of `v`, as the test compares them."""
    if isinstance(v, dict):
        return ("object", tuple(sorted((k, shape(x)) for k, x in v.items())))
    if isinstance(v, list):
        return ("array", tuple(sorted({shape(x) for x in v}, key=repr)))
    if isinstance(v, bool):
        return "bool"
    if isinstance(v, int):
        return "int"
    if isinstance(v, float):
        return "float"
    return "null" if v is None else "string"


def tidy(v):
    """`v` with floats rounded and long arrays shortened (every element shape kept)."""
    if isinstance(v, dict):
        return {k: tidy(x) for k, x in v.items()}
    if isinstance(v, list):
        if len(v) > 3:
            seen, kept = set(), []
            for i, x in enumerate(v):
                s = shape(x)
                if s not in seen or i < 2:
                    seen.add(s)
                    kept.append(x)
            v = kept
        return [tidy(x) for x in v]
    if isinstance(v, float):
        return float(f"{v:.6g}")
    return v


def main():
    exe = Path(sys.argv[1] if len(sys.argv) > 1 else "target/release/bistable").resolve()
    doc = Path(sys.argv[2] if len(sys.argv) > 2 else "docs/json.md")
    text = doc.read_text()
    with tempfile.TemporaryDirectory() as scratch:

        def fill(m):
            args = m.group(1).split()[1:]
            out = subprocess.run([str(exe), *args], cwd=scratch, check=True,
                                 capture_output=True, text=True).stdout
            example = json.dumps(tidy(json.loads(out)), indent=2, ensure_ascii=False)
            return f"```sh\n{m.group(1)}\n```\n```json\n{example}\n```"

        text = BLOCK.sub(fill, text)
    doc.write_text(text)


if __name__ == "__main__":
    main()
