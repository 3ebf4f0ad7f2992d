"""The campaign report in a real browser: tools/browser_check.py passes a generated page, fails broken ones.

Skipped when ``chromium`` is not on PATH, unless ``FDIKIT_REQUIRE_BROWSER=1`` (then a missing browser fails).
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
CHECK = ROOT / "tools" / "browser_check.py"

if shutil.which("chromium") is None:
    if os.environ.get("FDIKIT_REQUIRE_BROWSER") == "1":
        pytest.fail("FDIKIT_REQUIRE_BROWSER=1 but chromium is not on PATH (apt-get install -y chromium)",
                    pytrace=False)
    pytest.skip("chromium not on PATH (set FDIKIT_REQUIRE_BROWSER=1 to make this a failure)", allow_module_level=True)


def _report_helpers():
    spec = importlib.util.spec_from_file_location("campaign_test_report", Path(__file__).with_name("test_report.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _browser_check():
    spec = importlib.util.spec_from_file_location("browser_check", CHECK)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def run_check(page: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(CHECK), str(page), *args], capture_output=True, text=True,
                          timeout=120)


def test_a_generated_report_passes(tmp_path):
    from fdikit.campaign.report import write_report

    helpers = _report_helpers()
    folder = helpers.write_campaign(tmp_path / "c", helpers.synthetic_rows(designs=("bank",)))
    page = write_report(folder, replay=helpers.fake_replay(), examples=1)
    shot = tmp_path / "shot.png"
    res = run_check(page, "--screenshot", str(shot))
    assert res.returncode == 0, res.stderr
    assert shot.read_bytes()[1:4] == b"PNG"


FILLER = "<div style='height:1500px;background:linear-gradient(#fff,#36c)'>content</div>"


@pytest.mark.parametrize("script, message", [
    ("throw new Error('deliberate failure');", "uncaught exception"),
    ("console.error('deliberate console error');", "console.error: deliberate console error"),
    ("let x = ;", "uncaught exception"),
])
def test_console_errors_fail(tmp_path, script, message):
    page = tmp_path / "broken.html"
    page.write_text(f"<!DOCTYPE html><html><body>{FILLER}<script>{script}</script></body></html>")
    problems = _browser_check().check_page(page)
    assert len(problems) == 1 and message in problems[0], problems


def test_console_log_and_warn_pass(tmp_path):
    page = tmp_path / "ok.html"
    page.write_text(f"<!DOCTYPE html><html><body>{FILLER}<script>console.log('a'); console.warn('b');</script>"
                    "</body></html>")
    assert _browser_check().check_page(page) == []


def test_a_blank_page_fails(tmp_path):
    page = tmp_path / "blank.html"
    page.write_text("<!DOCTYPE html><html><body></body></html>")
    res = run_check(page)
    assert res.returncode == 1 and "blank page" in res.stderr, res.stderr


def test_a_missing_browser_is_reported(tmp_path):
    page = tmp_path / "p.html"
    page.write_text("<html></html>")
    env = {**os.environ, "PATH": str(tmp_path), "CHROMIUM": ""}
    res = subprocess.run([sys.executable, str(CHECK), str(page)], capture_output=True, text=True, env=env,
                         timeout=60)
    assert res.returncode == 2 and "apt-get" in res.stderr, res.stderr
