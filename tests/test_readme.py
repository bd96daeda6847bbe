"""The README's Python blocks run, and print what their comments say."""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

import pytest

README = Path(__file__).parents[1] / "README.md"


def test_readme_python_blocks_run(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)  # the examples write files (a checkpoint)
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
    assert blocks
    namespace: dict[str, object] = {}
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        for block in blocks:
            exec(compile(block, str(README), "exec"), namespace)
    lines = printed.getvalue().splitlines()
    # the first block's comments state these outputs
    assert lines[0].startswith("[ 0.25")
    assert "0.4330127" in lines[0]
    assert lines[1] == "0.0"
    assert lines[2] == "[2.  1.5]"
    assert lines[3] == "[5. 0. 0.] [ 0. 10.  0.]"
    assert lines[4].startswith("[6.9 0.  0. ] -0.95")
    # the many-body block: 4 frames (0.5 s apart up to 2 s), and it checkpointed
    assert lines[5].startswith("4 ")
    assert (tmp_path / "checkpoint.npz").exists()
