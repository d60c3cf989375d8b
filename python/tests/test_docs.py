"""Every ```python block of docs/python.md and the README runs (from a directory where
examples/ is the repository's), in order, sharing nothing but the file."""
import importlib.util
import os
import re

import pytest

BLOCK = re.compile(r"```python\n(.*?)```", re.S)


def blocks(path):
    return BLOCK.findall(path.read_text())


@pytest.mark.parametrize("doc", ["docs/python.md", "README.md"])
def test_documented_examples_run(doc, source_dir, tmp_path, monkeypatch, capsys):
    code = blocks(source_dir / doc)
    assert code, f"{doc} has no python example"
    os.symlink(source_dir / "examples", tmp_path / "examples")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    ran = 0
    for i, block in enumerate(code):
        needs = [m for m in ("pandas", "matplotlib") if re.search(rf"\b{m}\b|to_pandas", block)
                 and (m != "pandas" or "to_pandas" in block or "import pandas" in block)]
        if any(importlib.util.find_spec(m) is None for m in needs):
            continue  # optional packages absent: that block is not run
        exec(compile(block, f"{doc} block {i + 1}", "exec"), {"__name__": f"doc_{i}"})
        ran += 1
    assert ran >= 1
