"""The dashboard in headless Chromium (Playwright driving the Debian ``chromium``): the page
loads, lists the sensors, and a track appears and moves while a replay runs.

Playwright is in the ``dev`` extra. Where the Debian ``chromium`` is missing the tests install
it (``apt-get install chromium``, when running as root with apt; ``FUSETRACK_INSTALL_CHROMIUM=0``
turns that off) and are skipped only if that is impossible. The screenshot is kept in
``$FUSETRACK_ARTIFACTS`` (default: pytest's temporary directory).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import threading
from pathlib import Path

import pytest

from fusetrack.service.replay import demo_scenario, replay
from fusetrack.service.server import RunningNode, build_node

playwright = pytest.importorskip("playwright.sync_api")


def _find_chromium() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser")


def _install_chromium() -> str:
    """``apt-get install chromium`` (root only); the reason it could not, as a string."""
    if os.environ.get("FUSETRACK_INSTALL_CHROMIUM", "1") == "0":
        return "FUSETRACK_INSTALL_CHROMIUM=0"
    if not hasattr(os, "geteuid") or os.geteuid() != 0 or shutil.which("apt-get") is None:
        return "not root with apt-get: run `apt-get install chromium`"
    env = {**os.environ, "DEBIAN_FRONTEND": "noninteractive"}
    install = ["apt-get", "install", "-y", "-q", "--no-install-recommends", "chromium"]
    for cmd in (install, ["apt-get", "update", "-q"], install):
        try:
            done = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=900)
        except subprocess.TimeoutExpired:
            return f"{' '.join(cmd)} timed out"
        if cmd is install and done.returncode == 0:
            return ""
    return f"apt-get install chromium failed: {done.stderr.strip()[-200:]}"


@pytest.fixture(scope="module")
def chromium() -> str:
    """The system Chromium, installed on first use where possible."""
    path = _find_chromium()
    if path is None:
        why = _install_chromium()
        path = _find_chromium()
        if path is None:
            pytest.skip(f"no chromium on this machine ({why})")
    return path


def test_dashboard_shows_sensors_and_a_moving_track(network, chromium, tmp_path):
    scn = demo_scenario(network, seed=1, duration=15.0)
    out_dir = Path(os.environ.get("FUSETRACK_ARTIFACTS", tmp_path))
    out_dir.mkdir(parents=True, exist_ok=True)
    with RunningNode(build_node(network)) as node, playwright.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium, args=["--no-sandbox"])
        page = browser.new_page(viewport={"width": 1400, "height": 800})
        page.goto(node.url + "/")
        page.wait_for_function("document.querySelectorAll('#sensors tr').length === 4")
        assert page.locator("#sensors").inner_text().split()[0] == "mic_west"
        to = f"udp://{node.udp[0]}:{node.udp[1]}"
        sender = threading.Thread(
            target=replay, args=(scn.readings, network, to), kwargs={"speed": 10.0}
        )
        sender.start()
        page.wait_for_function(
            "Number(document.getElementById('tick').textContent) >= 5", timeout=30000
        )
        first = page.locator("#track").inner_text()
        page.wait_for_function(
            "Number(document.getElementById('tick').textContent) >= 25", timeout=30000
        )
        later = page.locator("#track").inner_text()
        sender.join(timeout=30)
        page.wait_for_timeout(1200)
        page.screenshot(path=str(out_dir / "dashboard.png"))
        status = page.locator("#status").inner_text()
        browser.close()
    assert "position (m)" in first and first != later  # the track moved
    assert status in ("ok", "degraded")
    assert (out_dir / "dashboard.png").stat().st_size > 10_000


@pytest.mark.parametrize(("scenario", "tracks"), [("two-targets", 2), ("grid", 1)])
def test_dashboard_shows_several_tracks_and_the_grid_estimate(scenario, tracks, chromium, tmp_path):
    """Two targets through MCMCDA give two tracks on the page; the grid tracker's estimate is
    drawn like any track (screenshots ``dashboard-two-targets.png``, ``dashboard-grid.png``)."""
    from fusetrack.service.replay import SCENARIOS
    from fusetrack.service.scenarios import NETWORKS

    cfg = NETWORKS[scenario](idle_flush=0.3)
    scn = SCENARIOS[scenario](cfg, seed=1, duration=20.0)
    out_dir = Path(os.environ.get("FUSETRACK_ARTIFACTS", tmp_path))
    out_dir.mkdir(parents=True, exist_ok=True)
    with RunningNode(build_node(cfg)) as node, playwright.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium, args=["--no-sandbox"])
        page = browser.new_page(viewport={"width": 1400, "height": 800})
        page.goto(node.url + "/")
        page.wait_for_function(
            f"document.querySelectorAll('#sensors tr').length === {len(cfg.sensors)}"
        )
        to = f"udp://{node.udp[0]}:{node.udp[1]}"
        sender = threading.Thread(
            target=replay, args=(scn.readings, cfg, to), kwargs={"speed": 8.0}
        )
        sender.start()
        page.wait_for_function(
            "Number(document.getElementById('tick').textContent) >= 60", timeout=40000
        )
        text = page.locator("#track").inner_text()
        shown = page.locator("#track tr.track").count()
        sender.join(timeout=30)
        page.wait_for_timeout(800)
        page.screenshot(path=str(out_dir / f"dashboard-{scenario}.png"))
        browser.close()
    if tracks > 1:
        assert shown == tracks and "#1" in text and "#2" in text
    else:
        assert "position (m)" in text
    assert (out_dir / f"dashboard-{scenario}.png").stat().st_size > 10_000
