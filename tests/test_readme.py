"""The README's Python examples run and diagnose their faults."""

import re
from pathlib import Path

ROOT = Path(__file__).parents[1]


def _blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), re.S)


def _result(code: str):
    ns: dict = {}
    exec(compile(code.replace("print(", "result = ("), "README.md", "exec"), ns)
    return ns["result"]


def test_readme_example_on_your_own_plant_and_log(tmp_path, monkeypatch):
    (tmp_path / "docs").symlink_to(ROOT / "docs")
    monkeypatch.chdir(tmp_path)
    code = _blocks()[0]
    assert len(code.strip().splitlines()) <= 15
    s = _result(code)
    assert s.detected and s.label == "level2_sensor" and s.isolation_correct and s.false_alarms == 0
    assert (tmp_path / "tanks.json").is_file()


def test_readme_example_on_a_builtin_plant():
    code = _blocks()[1]
    assert len(code.strip().splitlines()) <= 15
    s = _result(code)
    assert s.detected and s.label == "yaw_rate_sensor" and s.false_alarms == 0
