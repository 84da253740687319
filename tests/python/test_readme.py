"""Executable docs: the code blocks of README.md, fmu/README.md, ros/README.md and
crates/bistable-py/README.md, the CLI examples of README.md's command table and the Python
docstrings' examples.

Every fenced block either runs here (the Python blocks, as written, in a fresh interpreter) or
is preceded by an HTML comment `<!-- not run ...: reason -->` that says why not (make targets
that `make test` runs itself, long-running nodes, installs)."""

import doctest
import re
import shlex
import subprocess
import sys

import pytest

from conftest import ROOT

DOCS = ["README.md", "fmu/README.md", "ros/README.md", "crates/bistable-py/README.md"]
#: The documents whose Python blocks test_python_blocks_run_as_written runs.
PY_DOCS = ["README.md", "crates/bistable-py/README.md"]
FENCE = re.compile(r"^```(\w*)\n(.*?)^```\n", re.M | re.S)
NOT_RUN = re.compile(r"<!-- not run[^:]*: (\S.*?) -->\s*$")


def blocks(path):
    """`(language, code, the text before the block)` of every fenced block of a Markdown file."""
    text = (ROOT / path).read_text()
    return [(m.group(1), m.group(2), text[: m.start()]) for m in FENCE.finditer(text)]


def test_every_block_runs_here_or_says_why_not():
    seen = 0
    for path in DOCS:
        for lang, code, before in blocks(path):
            seen += 1
            if lang == "python" and path in PY_DOCS:
                continue  # run by test_python_blocks_run_as_written
            last = before.rstrip("\n").splitlines()[-1]
            assert NOT_RUN.search(last), (
                f"{path}: the {lang or 'plain'} block starting {code.splitlines()[0]!r} is "
                "neither run by tests/python/test_readme.py nor marked "
                "'<!-- not run by the README test: reason -->'"
            )
    assert seen >= 9


@pytest.mark.parametrize("path", PY_DOCS)
def test_python_blocks_run_as_written(tmp_path, path):
    """Each Python block, unchanged, in a fresh interpreter (no names from elsewhere; the
    README's sizes are those of this run)."""
    codes = [code for lang, code, _ in blocks(path) if lang == "python"]
    assert codes, f"{path} has no python block"
    for code in codes:
        r = subprocess.run(
            [sys.executable, "-c", code],
            cwd=tmp_path,
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert r.returncode == 0, f"{path}'s python block failed:\n{r.stderr}"
    if path != "README.md":
        return
    # What the block prints is what it says in its comment: the outcomes as a list of dicts.
    assert "[{'class': 'transient_interwell', 'period': 1, 'chaotic': False, 'final_well': 2, " \
        "'count': 5, 'fraction': 0.555" in r.stdout, r.stdout


def table_examples():
    """The `bistable ...` examples of the command table of README.md's CLI section."""
    text = (ROOT / "README.md").read_text()
    section = text[text.index("## The paper's analyses"): text.index("## Python")]
    rows = [line for line in section.splitlines() if line.startswith("| `")]
    examples = [re.findall(r"`(bistable [^`]*)`", row)[-1] for row in rows]
    assert len(examples) == len(rows) >= 8
    return examples


def small(args, out_dir):
    """A table example with small sizes: ranges `A:B:N` cut to 4 points, files in `out_dir`."""
    def cut(a):
        m = re.fullmatch(r"(-?[\d.]+):(-?[\d.]+):(\d+)", a)
        return f"{m.group(1)}:{m.group(2)}:4" if m and int(m.group(3)) > 4 else a

    return [str(out_dir / a.split("/", 1)[1]) if a.startswith("out/") else cut(a) for a in args]


def test_readme_cli_examples_run_with_small_sizes(cli, tmp_path):
    for example in table_examples():
        args = small(shlex.split(example)[1:], tmp_path)
        if args[0] == "map":
            args += ["--max-periods", "300"]
        r = subprocess.run([str(cli), *args], cwd=tmp_path, capture_output=True, text=True,
                           timeout=120)
        assert r.returncode == 0, f"{example}: {r.stderr}"
        for a in args:
            if a.startswith(str(tmp_path)):
                f = tmp_path / a[len(str(tmp_path)) + 1:]
                assert f.exists() and f.stat().st_size > 0, f"{example}: {f} not written"


def test_docstring_examples():
    import bistable_impact as bi

    modules = (bi, bi.sweep, bi.analyses, bi.cluster, bi.coexistence)
    for module in modules:
        result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
        assert result.failed == 0, module.__name__
    found = sum(
        len(t.examples)
        for m in modules
        for t in doctest.DocTestFinder().find(m)
    )
    assert found >= 15
