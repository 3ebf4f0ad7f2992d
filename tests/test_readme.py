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


def test_readme_campaign_spec_is_valid():
    import yaml

    from fdikit.campaign.plan import plan_runs
    from fdikit.campaign.spec import load_campaign

    (block,) = re.findall(r"```yaml\n(.*?)```", (ROOT / "README.md").read_text(), re.S)
    spec = load_campaign(yaml.safe_load(block))
    plan = plan_runs(spec)
    assert spec.name == "quick" and len(plan) == 300 and {p.fault for p in plan} >= {"none", "yaw_rate_sensor"}
