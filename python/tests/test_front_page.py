"""The Python blocks of the README and of docs/python.md run as written, each in a
fresh namespace, in a directory holding a copy of the checkout's scenarios (the blocks
name paths relative to a clone's root).

The shell blocks run in `tests/cli/front_page.rs`."""

import contextlib
import io
import os
import re
import shutil
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def python_blocks(text):
    return re.findall(r"```python\n(.*?)```", text, flags=re.S)


def test_every_readme_python_block_runs(tmp_path):
    blocks = python_blocks((REPO / "README.md").read_text())
    assert blocks, "README.md has no python block"
    shutil.copytree(REPO / "scenarios", tmp_path / "scenarios",
                    ignore=shutil.ignore_patterns("fmu"))
    here = os.getcwd()
    os.chdir(tmp_path)
    try:
        for block in blocks:
            printed = io.StringIO()
            with contextlib.redirect_stdout(printed):
                exec(compile(block, "README.md", "exec"), {})
            # The sweep's block prints the mean cost of each layout over its ok points.
            if "groupby" in block:
                means = printed.getvalue().split("\n")
                assert any("interleaved" in line for line in means), printed.getvalue()
    finally:
        os.chdir(here)


def test_every_python_block_of_the_python_guide_runs(tmp_path):
    blocks = python_blocks((REPO / "docs" / "python.md").read_text())
    assert len(blocks) >= 3, "docs/python.md has its python blocks"
    shutil.copytree(REPO / "scenarios", tmp_path / "scenarios",
                    ignore=shutil.ignore_patterns("fmu"))
    here = os.getcwd()
    os.chdir(tmp_path)
    try:
        for i, block in enumerate(blocks):
            with contextlib.redirect_stdout(io.StringIO()):
                exec(compile(block, f"docs/python.md block {i + 1}", "exec"), {})
    finally:
        os.chdir(here)
