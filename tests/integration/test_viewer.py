"""The HTML result viewer: data files, page size, and behaviour in a real headless Chromium.

Browser tests use playwright with the system Chromium (``ETORIGAMI_CHROMIUM`` or ``chromium``
on PATH, Debian's package); they are skipped when either is missing, except under CI (``CI`` set
to a true value; .ci/run sets it), where a missing browser is a failure.
"""

import io
import json
import os
import re
import shutil

import numpy as np
import pytest

from simulator import ParameterError, get_case
from simulator.viewer import load_viewer_data, viewer_html, write_viewer

BACKGROUND = (0xF4, 0xF5, 0xF7)


@pytest.fixture(scope="module")
def crane_dir(tmp_path_factory):
    case = get_case("crane", thermal_steps=40)
    result = case.run()
    assert result.success
    out = tmp_path_factory.mktemp("crane")
    result.save(out, {"case": case.name, "parameters": case.parameters})
    return out


@pytest.fixture(scope="module")
def page_file(crane_dir):
    return write_viewer(crane_dir)


# ------------------------------------------------------------------------------ Python side
def test_load_viewer_data_matches_saved_files(crane_dir):
    import pandas as pd

    data = load_viewer_data(crane_dir)
    m, n = data["temperature"].shape
    assert m == 41 and data["positions"].shape == (m, n, 3)
    frame = pd.read_csv(crane_dir / "creases.csv")
    last = frame[frame["step"] == m - 1].set_index("crease")
    np.testing.assert_allclose(data["fold_angle"][-1], last.loc[data["crease_ids"], "fold_angle [deg]"])
    assert list(data["stage"][:2]) == ["initial", "heat"] and data["increment"][-1] == 40


def test_crease_triangles_come_first_six_per_crease():
    # The page maps triangle 6c..6c+5 to crease c (click picking and highlight).
    mesh = get_case("crane", thermal_steps=1).model.mesh
    C = mesh.n_creases
    np.testing.assert_array_equal(mesh.crease_triangles, np.arange(6 * C).reshape(C, 6))


def test_page_is_self_contained(page_file, crane_dir):
    assert page_file == crane_dir / "viewer.html"
    text = page_file.read_text()
    assert "<title>etorigami: crane</title>" in text
    assert not re.search(r"<script[^>]*\bsrc=|<link[^>]*stylesheet|@import|https?://(?!www\.w3)", text)
    assert "/*__DATA__*/" not in text and "/*__SCRIPT__*/" not in text


def test_crane_500_increment_page_under_5_MB(crane_dir, tmp_path):
    """Page for 501 records of the crane mesh (records resampled from the 41 computed)."""
    data = load_viewer_data(crane_dir)
    s = np.linspace(0, len(data["temperature"]) - 1, 501)
    for key in ("positions", "temperature", "power", "fold_angle", "crease_temperature"):
        a = data[key]
        flat = a.reshape(len(a), -1)
        data[key] = np.stack([np.interp(s, np.arange(len(a)), col) for col in flat.T], axis=1
                             ).reshape((501,) + a.shape[1:])
    data["stage"] = np.array(["heat"] * 501)
    data["increment"] = np.arange(501)
    html = viewer_html(data)
    size = len(html.encode())
    assert size < 5e6
    assert json.loads(re.search(r'id="data" type="application/json">(.*?)</script>', html, re.S)
                      .group(1))["records"] == list(range(501))      # nothing thinned
    small = viewer_html(data, max_bytes=100_000)                      # thinned to fit a budget
    assert len(small.encode()) < 200_000


def test_records_without_time_are_null_in_the_page(tmp_path):
    """Quasi-static records have no time (NaN in the table): the page's data stays strict
    JSON (null, not NaN) and the time-domain step begins at t = 0."""
    from simulator import Heat, TransientHeat, simulate

    model = get_case("single_fold", thermal_steps=2).model
    simulate(model, [Heat({2: 1e-4}, increments=2),
                     TransientHeat({2: 1e-3}, duration=0.01, dt=5e-3)]).save(tmp_path)
    html = viewer_html(load_viewer_data(tmp_path))
    text = re.search(r'id="data" type="application/json">(.*?)</script>', html, re.S).group(1)

    def no_nan(name):
        raise AssertionError(f"{name} in the page data")
    data = json.loads(text, parse_constant=no_nan)
    assert data["time"] == [None, None, None, 0.0, 0.005, 0.01]


@pytest.mark.slow
def test_real_crane_500_increments_page_under_5_MB(tmp_path):
    case = get_case("crane")
    case.run().save(tmp_path, {"case": case.name, "parameters": case.parameters})
    assert write_viewer(tmp_path, tmp_path / "crane.html").stat().st_size < 5e6


def test_bad_result_dir_is_a_parameter_error(tmp_path, crane_dir):
    with pytest.raises(ParameterError, match="is not a directory"):
        write_viewer(tmp_path / "nowhere")
    with pytest.raises(ParameterError, match="has no nodes.npz, creases.csv, meta.json"):
        write_viewer(tmp_path)
    with pytest.raises(ParameterError, match="is a directory"):
        write_viewer(crane_dir, out=tmp_path)
    with pytest.raises(ParameterError, match="max_bytes"):
        viewer_html(load_viewer_data(crane_dir), max_bytes=0)
    broken = tmp_path / "broken"
    shutil.copytree(crane_dir, broken)
    with np.load(crane_dir / "nodes.npz") as npz:
        arrays = dict(npz)
    arrays["positions"][3, 0, 0] = np.nan
    np.savez(broken / "nodes.npz", **arrays)
    with pytest.raises(ParameterError, match="positions has non-finite values"):
        write_viewer(broken)
    del arrays["triangles"]
    np.savez(broken / "nodes.npz", **arrays)
    with pytest.raises(ParameterError, match="lacks triangles"):
        write_viewer(broken)


# ------------------------------------------------------------------------------ browser
def _chromium():
    path = os.environ.get("ETORIGAMI_CHROMIUM") or shutil.which("chromium") \
        or shutil.which("chromium-browser")
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        path = None
    if path is None:
        if _under_ci():
            pytest.fail("CI needs playwright and Debian's chromium for the viewer tests "
                        "(.ci/run installs them)")
        pytest.skip("playwright or chromium not installed")
    return path


def _under_ci() -> bool:
    """Whether ``CI`` is set to a true value (GitHub, GitLab and .ci/run set ``CI=true``)."""
    return os.environ.get("CI", "").strip().lower() not in ("", "0", "false", "no")


@pytest.mark.parametrize("ci, outcome", [("true", pytest.fail.Exception),
                                         ("1", pytest.fail.Exception),
                                         (None, pytest.skip.Exception),
                                         ("false", pytest.skip.Exception)])
@pytest.mark.parametrize("missing", ["chromium", "playwright"])
def test_missing_browser_fails_under_ci_and_skips_elsewhere(ci, outcome, missing, monkeypatch):
    """The skip decision of the browser tests: without Chromium (nothing on PATH, no
    ``ETORIGAMI_CHROMIUM``) or without playwright they fail under CI and skip elsewhere."""
    import sys

    monkeypatch.delenv("ETORIGAMI_CHROMIUM", raising=False)
    if ci is None:
        monkeypatch.delenv("CI", raising=False)
    else:
        monkeypatch.setenv("CI", ci)
    if missing == "chromium":
        monkeypatch.setenv("PATH", "")
        assert shutil.which("chromium") is None and shutil.which("chromium-browser") is None
    else:
        monkeypatch.setenv("ETORIGAMI_CHROMIUM", "/usr/bin/chromium")
        monkeypatch.setitem(sys.modules, "playwright.sync_api", None)     # import fails
    with pytest.raises(outcome):
        _chromium()


@pytest.fixture(scope="module")
def browser():
    path = _chromium()
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=path, args=["--no-sandbox"])
        yield b
        b.close()


@pytest.fixture
def page(browser, page_file):
    pg = browser.new_page(viewport={"width": 1200, "height": 760})
    pg.errors = []
    pg.on("console", lambda m: m.type in ("error", "warning") and pg.errors.append(m.text))
    pg.on("pageerror", lambda e: pg.errors.append(str(e)))
    pg.goto(page_file.as_uri())
    pg.wait_for_function("window.viewer && window.viewer.ready", timeout=20_000)
    yield pg
    pg.close()


def _canvas(page) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(page.locator("#scene").screenshot())).convert("RGB"))


def _mesh_pixels(img) -> int:
    return int((np.abs(img.astype(int) - BACKGROUND).sum(axis=2) > 30).sum())


def test_page_loads_without_console_errors(page):
    page.wait_for_timeout(300)
    assert page.errors == []
    assert page.title() == "etorigami: crane"
    assert page.evaluate("window.viewer.records") == 41
    start = page.evaluate("window.viewer.startRecord")          # the most folded record
    assert page.evaluate("window.viewer.record") == start > 0
    assert f"record {start}/40" in page.text_content("#record")


def test_screenshot_shows_the_mesh(page, tmp_path):
    page.evaluate("window.viewer.setRecord(40)")
    page.screenshot(path=str(tmp_path / "viewer.png"))
    img = _canvas(page)
    share = _mesh_pixels(img) / (img.shape[0] * img.shape[1])
    assert 0.02 < share < 0.9
    colours = {tuple(c) for c in img.reshape(-1, 3)[::7]}
    assert len(colours) > 50                          # shaded, temperature-coloured faces


def test_slider_changes_the_shape(page):
    page.evaluate("window.viewer.setRecord(0)")
    before = _canvas(page)
    page.focus("#slider")
    page.keyboard.press("End")
    page.wait_for_timeout(200)
    after = _canvas(page)
    assert page.evaluate("window.viewer.record") == 40
    assert "record 40/40 \u00b7 heat increment 40" in page.text_content("#record")
    changed = (np.abs(after.astype(int) - before).sum(axis=2) > 30).mean()
    assert changed > 0.01
    assert page.errors == []


def test_picked_crease_shows_its_fold_angle(page, crane_dir):
    data = load_viewer_data(crane_dir)
    page.evaluate("window.viewer.setRecord(40)")
    page.select_option("#crease", "3")
    page.wait_for_timeout(100)
    assert page.text_content("#fold") == f"{data['fold_angle'][40, 3]:.2f}"
    x, y = page.evaluate("window.viewer.creaseScreen(7)")
    box = page.locator("#scene").bounding_box()
    page.mouse.click(box["x"] + x, box["y"] + y)
    page.wait_for_timeout(100)
    assert page.evaluate("window.viewer.crease") == 7
    assert page.text_content("#fold") == f"{data['fold_angle'][40, 7]:.2f}"


def test_play_pause_and_drag_rotate(page):
    page.click("#play")
    page.wait_for_timeout(700)
    page.click("#play")
    stopped = page.evaluate("window.viewer.record")
    assert stopped > 0 and not page.evaluate("window.viewer.playing")
    page.wait_for_timeout(300)
    assert page.evaluate("window.viewer.record") == stopped
    before, yaw = _canvas(page), page.evaluate("window.viewer.view.yaw")
    box = page.locator("#scene").bounding_box()
    page.mouse.move(box["x"] + 300, box["y"] + 300)
    page.mouse.down()
    page.mouse.move(box["x"] + 420, box["y"] + 330, steps=6)
    page.mouse.up()
    page.wait_for_timeout(100)
    assert page.evaluate("window.viewer.view.yaw") != yaw
    assert (np.abs(_canvas(page).astype(int) - before).sum(axis=2) > 30).mean() > 0.01
    assert page.errors == []


# ------------------------------------------------------------------------------ issue 21, item 4
@pytest.fixture(scope="module")
def fold_dir(tmp_path_factory):
    case = get_case("single_fold", thermal_steps=20, gravity=True)
    result = case.run()
    assert result.success
    out = tmp_path_factory.mktemp("single_fold")
    result.save(out, {"case": case.name})
    return out


def test_viewer_opens_on_the_most_folded_record_and_crease(crane_dir):
    from simulator.io.viewer import _payload, _start

    data = load_viewer_data(crane_dir)
    change = np.abs(data["fold_angle"] - data["fold_angle"][:1])
    record, row = _start(data["fold_angle"])
    assert change.max(axis=1)[record] == change.max() and change[record, row] == change.max()
    payload = _payload(data, 10**7)
    assert (payload["start_record"], payload["start_crease"]) == (record, row)
    flat = np.zeros((3, 2))
    assert _start(flat) == (2, 0)                            # nothing folds: the last record


def test_saved_triangle_kinds_tell_substrate_from_panels(fold_dir, crane_dir):
    with np.load(fold_dir / "nodes.npz") as npz:
        kind, C = npz["triangle_kind"], len(npz["crease_ids"])
    assert set(np.unique(kind)) == {0, 1, 2}                 # crease, panels, substrate
    assert (kind[:6 * C] == 0).all()
    with np.load(crane_dir / "nodes.npz") as npz:
        assert 0 in npz["triangle_kind"] and 1 in npz["triangle_kind"]


def test_page_names_creases_by_id_labels_totals_and_has_a_scale(page, crane_dir):
    data = load_viewer_data(crane_dir)
    labels = page.locator("#crease option").all_text_contents()
    assert labels == [f"crease {int(c)}" for c in data["crease_ids"]]   # as creases.csv
    page.evaluate("window.viewer.setRecord(40)")
    page.select_option("#crease", "3")
    page.wait_for_timeout(100)
    record = page.text_content("#record")
    total = data["power"][40].sum() * 1e3
    assert f"total power (all creases) {total:.2f} mW" in record
    info = page.text_content("#crease-info")
    assert info.startswith(f"crease {int(data['crease_ids'][3])}: fold angle")
    assert f"power (this crease) {data['power'][40, 3] * 1e3:.3f} mW" in info
    scale = page.evaluate("window.viewer.scale")
    assert re.fullmatch(r"\d+(\.\d+)? (\u00b5m|mm)", scale), scale
    assert page.errors == []


def test_substrate_is_grey_and_named_in_the_legend(browser, fold_dir):
    pg = browser.new_page(viewport={"width": 1200, "height": 760})
    errors = []
    pg.on("pageerror", lambda e: errors.append(str(e)))
    pg.goto(write_viewer(fold_dir).as_uri())
    pg.wait_for_function("window.viewer && window.viewer.ready", timeout=20_000)
    assert pg.evaluate("window.viewer.substrate") > 0
    assert "substrate" in pg.text_content("#legend")
    img = _canvas(pg).astype(int)
    spread = img.max(axis=2) - img.min(axis=2)
    grey = (spread < 4) & (np.abs(img - BACKGROUND).sum(axis=2) > 30) & (img[..., 0] > 60)
    assert grey.mean() > 0.01                                 # the substrate, drawn in grey
    assert errors == []
    pg.close()
