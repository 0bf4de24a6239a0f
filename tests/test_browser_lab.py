"""The explorers' kernel-backed views in JupyterLab, driven in Chromium as a reader would.

Starts JupyterLab the way `make lab` does (``tools/lab.sh``: this clone's ``.venv`` kernel,
127.0.0.1, a random token) on a free port, with its runtime, config and data folders in a
temporary folder, and opens a small notebook that imports the explorers as the chapters
do and shows each one's ``.interactive()``. After running it, it moves delta and sigma on
each view (the LQG explorer has sigma only) and checks that the figure's PNG changes, that
the live learner shows its progress and that a move cancels its run, and that nothing is
printed to stderr and no view shows an error. The server is then stopped and its
processes and runtime files are gone. Without the kernel or the widgets' front end
(``jupyterlab-widgets``) it fails, saying which is missing.

On the same server, the views' accessibility: axe-core (``tests/test_browser_a11y.py``'s pinned
copy) reports no serious or critical violation inside the views, less :data:`EXCLUSIONS`, every
control has an accessible name and each figure has alt text; and a slider moved with the
keyboard alone (focus its handle, ArrowRight) redraws the figure for the new value.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from test_browser_a11y import FAILING, report

ROOT = Path(__file__).resolve().parents[1]
SHOTS = ROOT / "_build" / "screenshots"
VENV = ROOT / ".venv"
pytestmark = pytest.mark.browser
#: Bounds of each wait (ms): the build machine is shared, a cold kernel imports numba.
START_S = 120
KERNEL_MS = 180_000
DRAW_MS = 120_000

#: The notebook: the chapters' imports, then one view per explorer.
CELLS = [
    "import sys\nprint('kernel prefix:', sys.prefix)",
    "from safepg.thesis.explorers.curves import lqg_explorer, upsilon_explorer\n"
    "from safepg.thesis.explorers.live_learner import live_batch_size_explorer",
    "lqg_explorer().interactive()",
    "upsilon_explorer().interactive()",
    "live_batch_size_explorer().interactive()",
]
VIEWS = ["lqg", "upsilon", "live"]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def write_notebook(folder: Path) -> Path:
    import nbformat

    nb = nbformat.v4.new_notebook()
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    nb.cells = [nbformat.v4.new_code_cell(src) for src in CELLS]
    path = folder / "explorers.ipynb"
    nbformat.write(nb, path)
    return path


def write_settings(config: Path) -> None:
    """JupyterLab settings of the temporary config folder: every cell attached to the page
    (so every view is in the DOM), and no update or news check (no network here)."""
    user = config / "lab" / "user-settings" / "@jupyterlab"
    for ext, name, value in (("notebook-extension", "tracker", {"windowingMode": "none"}),
                             ("apputils-extension", "notification", {"checkForUpdates": False,
                                                                     "fetchNews": "false"})):
        (user / ext).mkdir(parents=True, exist_ok=True)
        (user / ext / f"{name}.jupyterlab-settings").write_text(json.dumps(value))


def processes_mentioning(text: str) -> list[str]:
    """Command lines of running processes that contain ``text`` (the kernels name their
    connection file, inside the temporary runtime folder)."""
    found = []
    for proc in Path("/proc").glob("[0-9]*"):
        try:
            cmd = (proc / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if text in cmd:
            found.append(f"{proc.name}: {cmd}")
    return found


class Lab:
    """A JupyterLab server started by tools/lab.sh, and what it wrote.

    The chapters' working copy goes to ``tmp/lab`` (``LAB_DIR``), never to this clone's lab/.
    By default the server shows ``tmp/notebooks`` (the explorers' notebook) with the test's
    settings; ``on_copy`` leaves it as `make lab` does: on the copy, with lab.sh's settings only.
    """

    def __init__(self, tmp: Path, on_copy: bool = False) -> None:
        self.tmp = tmp
        self.copy = tmp / "lab"
        self.notebooks = tmp / "notebooks"
        self.notebooks.mkdir()
        self.runtime = tmp / "runtime"
        args = ["--ServerApp.open_browser=False", "--LabApp.expose_app_in_browser=True"]
        if on_copy:
            (tmp / "config").mkdir()
        else:
            write_notebook(self.notebooks)
            write_settings(tmp / "config")
            args.insert(0, f"--ServerApp.root_dir={self.notebooks}")
        env = {**os.environ, "JUPYTER_CONFIG_DIR": str(tmp / "config"), "JUPYTER_RUNTIME_DIR": str(self.runtime),
               "JUPYTER_DATA_DIR": str(tmp / "data"), "IPYTHONDIR": str(tmp / "ipython"), "TMPDIR": str(tmp),
               "LAB_PORT": str(free_port()), "LAB_DIR": str(self.copy)}
        self.log_path = tmp / "lab.log"
        self.log = self.log_path.open("w")
        self.proc = subprocess.Popen(["bash", str(ROOT / "tools" / "lab.sh"), *args], cwd=ROOT, env=env,
                                     stdout=self.log, stderr=subprocess.STDOUT, start_new_session=True)
        self.info = self._wait_started()

    def _wait_started(self) -> dict[str, Any]:
        deadline = time.monotonic() + START_S
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                pytest.fail(f"JupyterLab exited with status {self.proc.returncode}:\n{self.log_text()}")
            for f in self.runtime.glob("jpserver-*.json"):
                try:
                    info = json.loads(f.read_text())
                except ValueError:  # being written
                    continue
                if self._answers(info):
                    return info
            time.sleep(0.3)
        pytest.fail(f"JupyterLab did not start in {START_S} s:\n{self.log_text()}")

    @staticmethod
    def _answers(info: dict[str, Any]) -> bool:
        try:
            urllib.request.urlopen(f"{info['url']}api/status?token={info['token']}", timeout=5).close()
            return True
        except (urllib.error.URLError, OSError):
            return False

    def log_text(self) -> str:
        self.log.flush()
        return self.log_path.read_text(errors="replace")[-4000:]

    def stop(self, timeout: float = 30) -> None:
        """SIGTERM to the server's process group (lab.sh and JupyterLab, which shuts its
        kernels down), SIGKILL if it has not stopped after ``timeout`` seconds."""
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGTERM)
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait(10)
        self.log.close()


def _serve(tmp_path_factory: Any, on_copy: bool = False) -> Iterator[Lab]:
    if not (VENV / "bin" / "jupyter-lab").exists():
        pytest.fail(f"{VENV}/bin/jupyter-lab is missing: run `make setup`")
    tmp = tmp_path_factory.mktemp("lab")
    server = Lab(tmp, on_copy)
    try:
        yield server
    finally:
        server.stop()
        # Nothing of the server is left: no kernel, no runtime file, no config file with the token.
        deadline = time.monotonic() + 15
        while processes_mentioning(str(tmp)) and time.monotonic() < deadline:
            time.sleep(0.3)
        left = processes_mentioning(str(tmp))
        files = [p.name for p in server.runtime.glob("*.json")] + [p.name for p in tmp.glob("safepg-lab-*")]
        shutil.rmtree(tmp, ignore_errors=True)
        assert not left, f"processes left running: {left}"
        assert not files, f"runtime files left: {files}"


@pytest.fixture(scope="module")
def lab(tmp_path_factory) -> Iterator[Lab]:
    yield from _serve(tmp_path_factory)


@pytest.fixture(scope="module")
def lab_on_copy(tmp_path_factory) -> Iterator[Lab]:
    yield from _serve(tmp_path_factory, on_copy=True)


DIGEST_JS = """async el => {
  const bytes = await (await fetch(el.src)).arrayBuffer();
  const d = new Uint8Array(await crypto.subtle.digest('SHA-256', bytes));
  return Array.from(d, x => x.toString(16).padStart(2, '0')).join('');
}"""

#: The control values a view's status line says the shown figure is for (None while computing).
DRAWN_JS = """el => { const s = el.querySelector('.safepg-status [data-params]');
                      return s ? JSON.parse(s.dataset.params) : null; }"""


class View:
    """One explorer's ipywidgets view in the page."""

    def __init__(self, page: Any, index: int) -> None:
        self.page = page
        self.el = page.locator(".safepg-interactive").nth(index)

    def status(self) -> str:
        return self.el.locator(".safepg-status").inner_text()

    def error(self) -> str:
        return self.el.locator(".safepg-error").inner_text().strip()

    def drawn(self) -> dict[str, Any] | None:
        return self.el.evaluate(DRAWN_JS)

    def wait_drawn(self, **want: Any) -> dict[str, Any]:
        """The drawn values, once the figure of values including ``want`` is shown."""
        handle = self.el.element_handle()
        self.page.wait_for_function(
            f"""([el, want]) => {{ const d = ({DRAWN_JS})(el); const img = el.querySelector('img.safepg-figure');
                  return d && img && img.src && img.complete && img.naturalWidth > 0
                         && Object.entries(want).every(([k, v]) => d[k] === v); }}""",
            arg=[handle, want], timeout=DRAW_MS)
        return self.drawn()

    def digest(self) -> str:
        return self.el.locator("img.safepg-figure").evaluate(DIGEST_JS)

    def set_slider(self, name: str, value: float) -> None:
        """Type ``value`` into the slider's readout and press Enter, as a reader can."""
        readout = self.el.locator(f".safepg-control-{name} .widget-readout")
        readout.click()
        readout.fill(str(value))
        readout.press("Enter")

    def select(self, name: str, label: str) -> None:
        """Pick the option shown as ``label`` (ipywidgets' options carry their labels, not their values)."""
        self.el.locator(f".safepg-control-{name} select").select_option(label=label)


#: The notebook's kernel has started (it answers, idle or busy: the widgets' manager asks it for its comms
#: as soon as it connects), or JupyterLab says in a dialog that none could be started.
KERNEL_STATE = """() => { if (document.querySelector('.jp-Dialog')) return 'dialog';
                          const w = window.jupyterapp && window.jupyterapp.shell.currentWidget;
                          const k = w && w.sessionContext && w.sessionContext.session
                                    && w.sessionContext.session.kernel;
                          return k && (k.status === 'idle' || k.status === 'busy') ? k.status : null; }"""


def kernel_state(page: Any) -> str | None:
    """Wait for the notebook's kernel to start; its status, ``'dialog'``, or None after KERNEL_MS."""
    from playwright.sync_api import Error, TimeoutError

    deadline = time.monotonic() + KERNEL_MS / 1000

    def left_ms() -> float:
        return max(1.0, (deadline - time.monotonic()) * 1000)

    while True:
        try:
            return page.wait_for_function(KERNEL_STATE, timeout=left_ms()).json_value()
        except TimeoutError:
            return None
        except Error:
            # JupyterLab navigates once it has read ?token= from the URL, destroying the context the wait
            # ran in: wait again in the new document once it has loaded.
            try:
                page.wait_for_load_state("domcontentloaded", timeout=left_ms())
            except TimeoutError:
                return None


def open_and_run(page: Any, lab: Lab) -> None:
    info = lab.info
    page.goto(f"{info['url']}lab/tree/explorers.ipynb?token={info['token']}")
    state = kernel_state(page)
    if state not in ("idle", "busy"):
        dialog = page.locator(".jp-Dialog").all_inner_texts()
        pytest.fail(f"the notebook has no running kernel (JupyterLab's dialog: {dialog}): is the kernel 'python3' "
                    f"of {VENV} registered? run `make setup`\n{lab.log_text()[-1500:]}")
    # Not awaited: evaluate has no timeout of its own; the output below has one.
    page.evaluate("() => { window.jupyterapp.commands.execute('notebook:run-all-cells'); }")
    page.locator(".jp-OutputArea-output", has_text="kernel prefix:").wait_for(timeout=KERNEL_MS)
    prefix = page.locator(".jp-OutputArea-output", has_text="kernel prefix:").inner_text().split(":", 1)[1].strip()
    assert Path(prefix).resolve() == VENV.resolve(), f"the kernel runs {prefix}, not this clone's {VENV}"
    # Either every view is drawn, or one shows as text: JupyterLab renders a widget's
    # text/plain only when no front end claims the widget's own type (no jupyterlab-widgets).
    page.wait_for_function(
        """n => document.querySelectorAll('.safepg-interactive').length >= n
               || [...document.querySelectorAll('.jp-OutputArea-output')].some(
                    e => e.textContent.startsWith('ExplorerView('))""", arg=len(VIEWS), timeout=KERNEL_MS)
    if page.locator(".safepg-interactive").count() < len(VIEWS):
        shown = page.locator(".jp-OutputArea-output").all_inner_texts()
        pytest.fail("the explorers' widgets were not rendered; the outputs show "
                    f"{[t[:120] for t in shown]}: is jupyterlab-widgets (the ipywidgets front end) installed?")


def test_explorers_respond_in_jupyterlab(browser, lab):
    started = time.monotonic()
    # http://127.0.0.1 only, and the token is required.
    assert lab.info["url"].startswith("http://127.0.0.1:") and len(lab.info["token"]) >= 32
    with pytest.raises(urllib.error.HTTPError) as no_token:
        urllib.request.urlopen(f"{lab.info['url']}api/kernels", timeout=10)
    assert no_token.value.code == 403

    page = browser.new_page(viewport={"width": 1400, "height": 2600})
    page_errors: list[str] = []
    page.on("pageerror", lambda e: page_errors.append(str(e)))
    try:
        open_and_run(page, lab)
        SHOTS.mkdir(parents=True, exist_ok=True)
        views = {name: View(page, i) for i, name in enumerate(VIEWS)}
        report: dict[str, Any] = {}

        # The live learner: a 3·10^6-trajectory run shows its progress, and the next move cancels it.
        live = views["live"]
        live.wait_drawn(budget="1000000")
        live.select("budget", "3,000,000")
        page.wait_for_function(
            """el => el.querySelector('.safepg-status').textContent.includes('Algorithm 4.1:')
                     && getComputedStyle(el.querySelector('.safepg-progress')).visibility === 'visible'""",
            arg=live.el.element_handle(), timeout=DRAW_MS)
        progress_line = live.status()
        live.el.screenshot(path=str(SHOTS / "lab-live-progress.png"))
        moved = time.monotonic()
        live.select("budget", "30,000")
        live.wait_drawn(budget="30000")
        report["live: 3e6 run cancelled, 3e4 figure after (s)"] = round(time.monotonic() - moved, 2)
        report["live: progress line"] = progress_line
        assert "computing…" in progress_line and "trajectories" in progress_line

        for name, view in views.items():
            view.el.scroll_into_view_if_needed()
            first = view.wait_drawn()
            moves = [("sigma", 0.5)] if name == "lqg" else [("delta", 0.5), ("sigma", 1.5)]
            for control, value in moves:
                before = view.digest()
                view.set_slider(control, value)
                drawn = view.wait_drawn(**{control: value})
                after = view.digest()
                assert after != before, f"{name}: moving {control} to {value} did not change the figure"
                assert view.error() == "", f"{name}: {view.error()}"
                report[f"{name}: {control} -> {value}"] = {"status": view.status(), "text": view.el.locator(
                    ".safepg-text").inner_text()[:160]}
            assert drawn != first
            view.el.screenshot(path=str(SHOTS / f"lab-{name}.png"))

        stderr = page.locator('.jp-OutputArea-output[data-mime-type="application/vnd.jupyter.stderr"]')
        assert stderr.count() == 0, stderr.all_inner_texts()
        errors = page.locator('.jp-OutputArea-output[data-mime-type="application/vnd.jupyter.error"]')
        assert errors.count() == 0, errors.all_inner_texts()
        assert not [e for e in page_errors if "widget" in e.lower()], page_errors
        page.screenshot(path=str(SHOTS / "lab-notebook.png"), full_page=True)
        report["wall time of the test body (s)"] = round(time.monotonic() - started, 1)
        (SHOTS / "lab_report.json").write_text(json.dumps(report, indent=1, ensure_ascii=False))
        print("\n" + json.dumps(report, indent=1, ensure_ascii=False))
    finally:
        page.close()


def _book_state() -> tuple[str, dict[str, str]]:
    """``git status --porcelain book/`` and the bytes' hashes of every file of book/."""
    import hashlib

    status = subprocess.run(["git", "status", "--porcelain", "book/"], cwd=ROOT, capture_output=True, text=True,
                            check=True).stdout
    files = {str(p.relative_to(ROOT)): hashlib.sha256(p.read_bytes()).hexdigest()
             for p in sorted((ROOT / "book").rglob("*")) if p.is_file()}
    return status, files


#: The chapter edited in the test: small, no experiment.
CHAPTER = "adaptive_step.ipynb"
MARK = "# edited in JupyterLab by test_browser_lab"


def test_a_save_in_jupyterlab_changes_the_copy_never_book(browser, lab_on_copy):
    lab = lab_on_copy
    before = _book_state()
    info = lab.info
    page = browser.new_page(viewport={"width": 1400, "height": 1200})
    try:
        # The file browser shows the chapters of the copy, not book/'s plumbing.
        page.goto(f"{info['url']}lab?token={info['token']}")
        page.locator(".jp-DirListing-item", has_text=CHAPTER).wait_for(timeout=KERNEL_MS)
        listed = {t.strip() for t in page.locator(".jp-DirListing-item .jp-DirListing-itemText").all_inner_texts()}
        chapters = {p.name for p in (ROOT / "book").glob("*.ipynb")} | {"intro.md"}
        assert chapters <= listed, f"the file browser lists {sorted(listed)}"
        assert not listed & {"_ext", "_vendor", "_static_safepg", "tools", "_downloads"}, sorted(listed)

        # Open a chapter, change its first code cell, save with Ctrl-S.
        page.goto(f"{info['url']}lab/tree/{CHAPTER}?token={info['token']}")
        editor = page.locator(".jp-Notebook .jp-CodeCell .cm-content").first
        editor.wait_for(timeout=KERNEL_MS)
        editor.click()
        page.keyboard.press("Control+End")
        page.keyboard.type("\n" + MARK)
        page.keyboard.press("Control+s")
        saved = lab.copy / CHAPTER
        deadline = time.monotonic() + 60
        while MARK not in saved.read_text() and time.monotonic() < deadline:
            time.sleep(0.3)
        assert MARK in saved.read_text(), "Ctrl-S did not save the chapter into the copy"
        # JupyterLab never wrote book/: its git status and every file are as before.
        assert _book_state() == before
        assert MARK not in (ROOT / "book" / CHAPTER).read_text()
        if not before[0]:
            assert _book_state()[0] == "", "git status --porcelain book/ is not empty"
        # No news popup: the server's settings for it are lab.sh's overrides (this server has no
        # user settings of the test's). Asking the server is a fact; watching for a popup that
        # may come later would be a guessed wait.
        url = f"{info['url']}lab/api/settings/@jupyterlab/apputils-extension:notification?token={info['token']}"
        with urllib.request.urlopen(url, timeout=30) as r:
            plugin = json.load(r)
        # What JupyterLab uses: the user's settings over the schema's defaults, which the
        # overrides replace.
        notification = {k: v.get("default") for k, v in plugin["schema"]["properties"].items()}
        notification.update(plugin["settings"])
        assert notification.get("fetchNews") == "false", notification
        assert notification.get("checkForUpdates") is False, notification
        assert page.get_by_text("Jupyter news").count() == 0, "JupyterLab asked about Jupyter news"
        SHOTS.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(SHOTS / "lab-copy-saved.png"))
    finally:
        page.close()


# --------------------------------------------------------------------------- accessibility
#: axe on the views only (JupyterLab's own chrome is not ours).
AXE_VIEWS = """async () => {
  const r = await axe.run({include: [['.safepg-interactive']]}, {resultTypes: ['violations'], preload: false});
  return r.violations.map(v => ({id: v.id, impact: v.impact, help: v.help,
    nodes: v.nodes.map(n => ({target: n.target.join(' '), impact: n.impact}))}));
}"""

#: Every focusable control of a view, its accessible name as axe computes it, and whether an
#: exclusion covers it.
NAMES = """(el, excluded) => { axe.setup(document); try {
  return [...el.querySelectorAll('input, select, textarea, button, [role=slider], [contenteditable=true]')]
    .filter(c => c.offsetParent !== null)
    .map(c => [c.tagName.toLowerCase() + (c.getAttribute('role') ? '[' + c.getAttribute('role') + ']' : '')
               + ' in ' + ((c.closest('[class*=safepg-control-]') || {}).className || '?'),
               axe.commons.text.accessibleTextVirtual(axe.utils.getNodeFromTree(c)).trim(),
               !!(excluded && c.matches(excluded))]);
} finally { axe.teardown(); } }"""


#: Violations inside the views that we cannot fix from our files, ``(rule, CSS selector of the
#: node, why)``; each is checked to exist, so a fixed one must leave the list.
EXCLUSIONS: list[tuple[str, str, str]] = [
    ("aria-input-field-name", ".widget-slider [role=slider]",
     "ipywidgets 8 draws a slider with noUiSlider, whose handle (role=slider) it does not name: "
     "its description is a separate <label> and no trait reaches the handle's aria-label"),
]


@pytest.fixture(scope="module")
def views_page(browser: Any, lab: Lab) -> Iterator[tuple[Any, dict[str, View], list[str]]]:
    """The explorers' notebook opened and run once for the accessibility tests, which read it
    (axe) and then move one slider on each view (the keyboard test, last in this file)."""
    page = browser.new_page(viewport={"width": 1400, "height": 2600})
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    open_and_run(page, lab)
    views = {name: View(page, i) for i, name in enumerate(VIEWS)}
    for view in views.values():
        view.wait_drawn()
    try:
        yield page, views, errors
    finally:
        page.close()


def test_views_pass_axe(views_page, axe_js):
    """axe-core inside the views (less :data:`EXCLUSIONS`), and every control named."""
    page, views, errors = views_page
    page.add_script_tag(content=axe_js)
    excluded = {rule: page.evaluate("s => [...document.querySelectorAll(s)].length", sel)
                for rule, sel, _ in EXCLUSIONS}
    assert all(excluded.values()), f"an exclusion matches nothing any more: {excluded}"
    found = []
    for v in page.evaluate(AXE_VIEWS):
        sel = next((s for r, s, _ in EXCLUSIONS if r == v["id"]), None)
        nodes = [n for n in v["nodes"] if (n["impact"] or v["impact"]) in FAILING
                 and not (sel and page.evaluate(
                     "([t, s]) => { const e = document.querySelector(t); return !!(e && e.matches(s)); }",
                     [n["target"], sel]))]
        if nodes:
            found.append({**v, "nodes": nodes})
    problems = report("JupyterLab views", found)
    excluded_selectors = ", ".join(sel for _, sel, _ in EXCLUSIONS)
    for name, view in views.items():
        nameless = [what for what, label, node_ok in view.el.evaluate(NAMES, excluded_selectors)
                    if not label and not node_ok]
        if nameless:
            problems.append(f"{name}: controls without an accessible name: {nameless}")
    assert not errors, errors
    alts = page.evaluate("() => [...document.querySelectorAll('.safepg-interactive img.safepg-figure')]"
                         ".map(img => img.alt)")
    assert len(alts) == len(views) and all(len(a.split()) >= 8 for a in alts), alts
    assert not problems, "\n".join(problems)


def test_sliders_move_by_keyboard(views_page):
    """Focus each view's sigma slider handle, press ArrowRight: the figure is redrawn for the new value."""
    page, views, errors = views_page
    for name, view in views.items():
        view.el.scroll_into_view_if_needed()
        before = view.wait_drawn()
        digest = view.digest()
        handle = view.el.locator(".safepg-control-sigma [role=slider]")
        assert handle.get_attribute("tabindex") == "0", f"{name}: the slider is not in the tab order"
        handle.focus()
        assert handle.evaluate("e => e === document.activeElement")
        page.keyboard.press("ArrowRight")
        page.wait_for_function(
            """([el, old]) => { const s = el.querySelector('.safepg-status [data-params]');
                 return s && String(JSON.parse(s.dataset.params).sigma) !== String(old); }""",
            arg=[view.el.element_handle(), before["sigma"]], timeout=120_000)
        after = view.wait_drawn()
        assert float(after["sigma"]) > float(before["sigma"]), (name, before, after)
        assert view.digest() != digest, f"{name}: the figure did not change after ArrowRight on sigma"
    assert not errors, errors
