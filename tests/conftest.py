"""Shared fixtures: the paper's example design and its analysis, a running studio
server with one browser-like tab per test, and a recorder of the files a tab sends."""

from __future__ import annotations

import time

import pytest
from fake_tab import FakeTab

from camcore.analysis import analyze
from camcore.model import load_preset


def wait_for(pred, timeout=10.0) -> bool:
    """Poll ``pred`` until true (True) or ``timeout`` seconds pass (False)."""
    t0 = time.time()
    while time.time() - t0 < timeout:
        if pred():
            return True
        time.sleep(0.02)
    return False


@pytest.fixture(scope="session")
def paper():
    """The paper's Section 6 example (double concave faces)."""
    return load_preset("paper_example")


@pytest.fixture(scope="session")
def paper_analysis(paper):
    """Its fast analysis (not verified); shared, so tests must not modify it."""
    return analyze(paper, verify=False)


@pytest.fixture(scope="module")
def app():
    """A studio server on a free local port, without its animation loops."""
    from app.main import App

    a = App(host="127.0.0.1", port=0)
    yield a
    a.stop()


@pytest.fixture()
def tab(app):
    """The Session of a new browser-like tab (tests/fake_tab.py) of ``app``."""
    before = set(app.sessions)
    t = FakeTab(app.port)
    assert wait_for(lambda: set(app.sessions) - before), "no session for the new tab"
    (cid,) = set(app.sessions) - before
    s = app.sessions[cid]
    yield s
    t.close()
    wait_for(lambda: cid not in app.sessions)


@pytest.fixture()
def downloads(tab):
    """Files the tab sends to its browser, as (name, bytes), newest last."""
    sent: list[tuple[str, bytes]] = []
    tab.client.send_file_download = lambda name, data, **kw: sent.append((name, data))
    return sent
