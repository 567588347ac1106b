"""Regenerate the README screenshots: the studio in headless Chromium at 1920x1080.

    python3 docs/screenshots/make.py

Writes studio_station2.png (the teaching view at station 2, Front camera),
contact_closeup.png (the close-up camera there), curves.png (the designer's curves in
the wide panel), stations.png (the stations diagram) and explore.png (the Explore tab's map of a
base radius x offset sweep over the four followers and its front of three figures, as
camcore.explore draws it).
"""

from __future__ import annotations

from pathlib import Path

HERE = Path(__file__).resolve().parent
FLAGS = ["--use-gl=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist"]


def studio() -> None:
    from playwright.sync_api import sync_playwright

    from app.main import App

    app = App(host="127.0.0.1", port=0)
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path="/usr/bin/chromium", args=FLAGS)
            page = browser.new_page(viewport={"width": 1920, "height": 1080})
            page.set_default_timeout(60_000)
            page.goto(f"http://127.0.0.1:{app.port}/")
            page.get_by_text("All design limits met").first.wait_for()
            page.get_by_role("button", name="2", exact=True).click()
            page.get_by_text("at station 2").first.wait_for()
            page.mouse.move(960, 1000)  # (off the buttons: their hint would cover the panel)
            page.wait_for_timeout(4000)  # software WebGL: a few frames per second
            page.screenshot(path=str(HERE / "studio_station2.png"))
            page.get_by_role("tab", name="View").click()
            page.get_by_role("button", name="Contact close-up").click()
            page.wait_for_timeout(4000)
            page.screenshot(path=str(HERE / "contact_closeup.png"))
            page.get_by_role("button", name="Front").click()
            page.get_by_role("tab", name="Curves").click()
            page.get_by_text("Wide panel").first.click()
            page.wait_for_timeout(3000)
            page.screenshot(path=str(HERE / "curves.png"))
            browser.close()
    finally:
        app.stop()


def stations() -> None:
    from camcore.analysis import analyze
    from camcore.document import stations_png
    from camcore.model import load_preset

    (HERE / "stations.png").write_bytes(stations_png(analyze(load_preset("paper_example"))))


def explore_map() -> None:
    from camcore import explore, sweep
    from camcore.model import PAPER_FOLLOWERS, load_preset

    base = load_preset("paper_example").model_dump(mode="json")
    x, y = ("cam.base_radius_mm", 50.0, 110.0), ("follower.offset_mm", 10.0, 45.0)
    points = explore.grid_points(explore.sweep_grid(x, y, 8, [k.value for k in PAPER_FOLLOWERS]))
    rows = sweep.run_chunk(base, points, verify=False)
    names = ["cam_size", "stress", "pressure_angle"]  # the third colours the designs
    png = explore.explore_png(
        rows,
        (x[0], "Base radius r_b [mm]"),
        (y[0], "Offset e (double) [mm]"),
        names,
        explore.pareto(rows, names),
        1000,  # as in the wide panel
    )
    (HERE / "explore.png").write_bytes(png)


if __name__ == "__main__":
    studio()
    stations()
    explore_map()
