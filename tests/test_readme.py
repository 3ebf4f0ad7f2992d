"""The README's Python example runs and detects its fault."""

import re
from pathlib import Path


def test_readme_example_runs():
    text = (Path(__file__).parents[1] / "README.md").read_text()
    code = re.search(r"```python\n(.*?)```", text, re.S).group(1)
    assert len(code.strip().splitlines()) <= 15
    ns: dict = {}
    exec(compile(code.replace("print(", "result = ("), "README.md", "exec"), ns)
    s = ns["result"]
    assert s.detected and s.label == "yaw_rate_sensor" and s.false_alarms == 0
