"""The README's 10-line example (the first python block of its "Python" section) runs as
written from the repository root and does what it says."""

import re

import numpy as np

from conftest import ROOT


def readme_example() -> str:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text[text.index("\n## Python\n") :]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def test_the_readme_example_runs(monkeypatch, capsys):
    code = readme_example()
    assert len(code.strip().splitlines()) <= 10
    monkeypatch.chdir(ROOT)
    scope: dict = {}
    exec(compile(code, "README.md", "exec"), scope)
    printed = capsys.readouterr().out.splitlines()
    result, colours = scope["result"], scope["colours"]
    assert len(printed) == len(result.detections) >= 5
    assert colours.shape == (len(scope["points"]), 3)
    grey = np.all(colours == [0.6, 0.6, 0.6], axis=1)
    assert np.array_equal(grey, result.labels == -1), "grey exactly where no seat is"
