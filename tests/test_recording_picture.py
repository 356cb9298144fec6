"""tools/recording_picture.py, the docs' picture of a recording's default view: its DevTools pipe framing and its
clear refusal where the viewer or Chromium is missing (a picture itself needs Chromium, which CI lacks)."""

from __future__ import annotations

import importlib.util
import json
import os

import pytest
from checks import ROOT


def _tool():
    spec = importlib.util.spec_from_file_location("recording_picture", ROOT / "tools" / "recording_picture.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_devtools_messages_are_nul_ended_json_answered_by_id():
    """A command goes out as one NUL-ended JSON message; events and other ids before the answer are skipped, an
    answer split over reads is joined, an error answer is raised with the method's name."""
    tool = _tool()
    to_browser, from_browser = os.pipe(), os.pipe()
    pipe = tool.DevToolsPipe(to_browser[1], from_browser[0])
    answers = [{"method": "Target.targetCreated", "params": {}}, {"id": 7, "result": {}}, {"id": 1, "result": {"x": 2}}]
    wire = b"".join(json.dumps(a).encode() + b"\0" for a in answers)
    os.write(from_browser[1], wire[:10])
    os.write(from_browser[1], wire[10:])
    assert pipe.call("Page.captureScreenshot", session="s1", format="png") == {"x": 2}
    sent = os.read(to_browser[0], 1 << 16)
    assert sent.endswith(b"\0")
    assert json.loads(sent[:-1]) == {
        "id": 1,
        "method": "Page.captureScreenshot",
        "params": {"format": "png"},
        "sessionId": "s1",
    }
    os.write(from_browser[1], json.dumps({"id": 2, "error": {"message": "no such target"}}).encode() + b"\0")
    with pytest.raises(RuntimeError, match=r"Target\.attachToTarget.*no such target"):
        pipe.call("Target.attachToTarget", targetId="x")


def test_without_chromium_it_says_what_to_install(monkeypatch, capsys, tmp_path):
    tool = _tool()
    monkeypatch.setattr(tool.shutil, "which", lambda name: "/usr/bin/rerun" if name == "rerun" else None)
    monkeypatch.setattr("sys.argv", ["recording_picture.py", str(tmp_path / "run.rrd"), str(tmp_path / "a.png")])
    assert tool.main() == 2
    assert "Chromium (apt-get install chromium)" in capsys.readouterr().err
    monkeypatch.setattr("sys.argv", ["recording_picture.py", "a.rrd", "a.png", "--size", "big"])
    assert tool.main() == 2
    assert "WIDTHxHEIGHT" in capsys.readouterr().err
