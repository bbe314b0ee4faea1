"""The README's Python example runs as written, from the repository's root."""

import os
import re


def test_the_readme_example_runs(repo, capsys):
    text = (repo / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert len(blocks) == 1, "the README holds one Python example"
    here = os.getcwd()
    os.chdir(repo)
    try:
        exec(compile(blocks[0], "README.md", "exec"), {})
    finally:
        os.chdir(here)
    printed = capsys.readouterr().out
    assert printed.startswith("Modes(") and "Update(" in printed and ", converged," in printed, printed
