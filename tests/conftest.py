"""Shared fixtures: the built book and Debian's headless Chromium for the browser tests, and
``views`` for the tests of the explorers' kernel views; the ``node`` marker and the skip report.

``book`` builds the book once per test run, as ``make book`` does (notebook execution goes
through the Jupyter Book cache, so a rebuild with unchanged notebooks takes seconds); under
pytest-xdist the first worker to ask builds it and the others wait for it;
``browser`` launches ``/usr/bin/chromium`` through Playwright, never a downloaded
browser. Without Chromium (or Playwright) the browser tests are skipped, except under
``CI=true``, where they fail: CI must not pass by skipping them (``make browser-deps``
installs Chromium). A test asks for ``browser`` before ``book``, so a skipped test does
not build the book first. Only one Playwright instance may run per process: every
browser test shares this one.

Every test that needs something of the machine goes through :func:`skip_or_fail`: the tests
marked ``node`` (Node.js runs the page's JavaScript; ``make node-deps`` installs Debian's
``nodejs``) as the browser tests do, and the others that need a program or a package that
``make test`` installs. Under ``CI=true`` such a test fails with the package to install instead
of skipping. Every run ends with the list of its skips (``skip_report.SkipReport``); under
``CI=true`` a skip that the README's list of skips does not name fails the run.
"""

from __future__ import annotations

import fcntl
import os
import shutil
import subprocess
import sys
import tarfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[1]
HTML = ROOT / "_build" / "html"
SHOTS = ROOT / "_build" / "screenshots"
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
#: Node.js, which runs the page's JavaScript against safepg (the tests marked ``node``); None if missing.
NODE = shutil.which("node")
#: The jupyter-book of the interpreter running the tests (.venv's under `make test`), not the
#: first one on the PATH: that one would build the book with another environment's safepg.
JUPYTER_BOOK = str(Path(sys.executable).with_name("jupyter-book"))
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--no-first-run"]


def pytest_configure(config: pytest.Config) -> None:
    """Under pytest-xdist, numba's parallel kernels start on one thread in each worker; the process that
    reports the run lists its skips (``skip_report.SkipReport``).

    The workers already share the cores; with numba's threads on every core too, two workers'
    parallel regions wait on each other's descheduled threads (a module's setup took 56 s instead
    of 9). A test that asks for more threads gets them (``numba.set_num_threads``), and a seeded
    run gives the same numbers on any number of threads (``tests/test_streams.py``).
    """
    if hasattr(config, "workerinput"):
        import numba

        numba.set_num_threads(1)
    else:  # the process that reports the run (pytest-xdist's controller, or the only one)
        from skip_report import SkipReport

        config.pluginmanager.register(SkipReport(ci=in_ci()), "safepg-skip-report")


def in_ci() -> bool:
    """True when the environment says this is a CI run (``CI=true``)."""
    return os.environ.get("CI", "").strip().lower() in ("true", "1", "yes")


def skip_or_fail(reason: str, allow_module_level: bool = False) -> None:
    """Skip the test, or fail it under CI: what ``make test`` installs is there in CI, so a test that
    finds it missing must not pass by skipping. ``reason`` names what to install; with
    ``allow_module_level``, called at a module's import, it skips (or fails) the whole module."""
    if in_ci():
        pytest.fail(f"{reason} (CI=true: this test must run, not skip)")
    pytest.skip(reason, allow_module_level=allow_module_level)


def require_node() -> str:
    """The path of Node.js; :func:`skip_or_fail` without it."""
    if NODE is None:
        skip_or_fail("node is missing: run `make node-deps` (apt-get install nodejs)")
    assert NODE is not None
    return NODE


def import_or_fail(module: str, requirements: str = "requirements.txt") -> Any:
    """``module`` imported; else :func:`skip_or_fail` (the whole module when called at its import), naming
    the file that pins it (``make setup`` installs requirements.txt, ``make setup-dev`` requirements-dev.txt)."""
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError:
        skip_or_fail(f"{module} is not installed: run `make setup setup-dev` (it is pinned in {requirements})",
                     allow_module_level=True)


def extract_archive(tar: tarfile.TarFile, dest: str | os.PathLike[str]) -> None:
    """Extract ``tar`` into ``dest`` as ``tar.extractall(dest, filter="data")`` does, on any Python 3.11.

    The ``filter`` argument came with Python 3.11.4; Debian 12's python3 is 3.11.2. There each member is
    checked as the data filter checks it, just before it is extracted (a symlink extracted earlier is
    followed): a :class:`tarfile.TarError` refuses an absolute name (which the data filter would extract
    under ``dest`` with its leading ``/`` stripped), a name or a link whose real path leaves ``dest``, an
    absolute link, and anything but a regular file, a directory or a link (devices, pipes). Regular files
    get the data filter's mode (no setuid/setgid/sticky, no write for group and others, owner rw) and
    their mtime, folders the umask's mode; no owner is set.
    """
    if hasattr(tarfile, "data_filter"):
        tar.extractall(dest, filter="data")
        return
    import inspect

    root = os.path.realpath(dest)
    os.makedirs(root, exist_ok=True)
    # A tarfile that takes filters (this branch meets one only in its test) applies none: the checks below are it.
    trusted = {"filter": "fully_trusted"} if "filter" in inspect.signature(tar.extract).parameters else {}

    def inside(path: str) -> bool:
        return os.path.commonpath([os.path.realpath(path), root]) == root

    for member in tar.getmembers():
        name = member.name
        if name.startswith(("/", os.sep)) or os.path.isabs(name):
            raise tarfile.TarError(f"{name!r}: absolute path")
        if not inside(os.path.join(root, name)):
            raise tarfile.TarError(f"{name!r} would be extracted outside {root}")
        if not (member.isreg() or member.isdir() or member.issym() or member.islnk()):
            raise tarfile.TarError(f"{name!r}: special file (device, pipe), refused")
        if member.issym() or member.islnk():
            if os.path.isabs(member.linkname):
                raise tarfile.TarError(f"{name!r}: link to the absolute path {member.linkname!r}")
            base = os.path.join(root, os.path.dirname(name)) if member.issym() else root
            if not inside(os.path.join(base, member.linkname)):
                raise tarfile.TarError(f"{name!r}: link to {member.linkname!r}, outside {root}")
        path = os.path.join(root, name)
        if member.isdir():  # the umask's mode, as the data filter gives (tarfile would make it 0o700)
            os.makedirs(path, exist_ok=True)
            continue
        tar.extract(member, root, set_attrs=False, **trusted)
        if member.isreg():
            mode = member.mode & 0o755
            os.chmod(path, (mode if mode & 0o100 else mode & ~0o111) | 0o600)
            os.utime(path, (member.mtime, member.mtime))


def pytest_runtest_setup(item: pytest.Item) -> None:
    """A test marked ``node`` needs Node.js (:func:`require_node`)."""
    if item.get_closest_marker("node") is not None:
        require_node()


def build_book() -> Path:
    """Fetch the vendored assets, compute what the chapters need and build the book with warnings as errors.

    Returns
    -------
    Path
        ``_build/html``.
    """
    subprocess.run(["bash", "book/tools/vendor_assets.sh"], cwd=ROOT, check=True)
    subprocess.run(["bash", "book/tools/cache_guard.sh"], cwd=ROOT, check=True)
    # As `make book`: the chapters' experiments first (progress lines), then the pages from the stored runs.
    subprocess.run([sys.executable, "-m", "safepg", "run-book"], cwd=ROOT, check=True)
    subprocess.run([sys.executable, "book/tools/execute_pages.py"], cwd=ROOT, check=True)
    subprocess.run([JUPYTER_BOOK, "build", ".", "-W", "-n", "--keep-going"], cwd=ROOT, check=True,
                   stdout=subprocess.DEVNULL)
    return HTML


@pytest.fixture(scope="session")
def book(request, tmp_path_factory) -> Path:
    """The book, built once per test run; ``_build/html``.

    Each pytest-xdist worker is a session of its own: they share a folder (the parent of their
    temporary folders), where a lock lets one build while the others wait, and a file says it is built.
    """
    shared = tmp_path_factory.getbasetemp()
    if hasattr(request.config, "workerinput"):
        shared = shared.parent
    with (shared / "book.lock").open("w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        built = shared / "book-built"
        if not built.exists():
            build_book()
            built.touch()
    return HTML


@pytest.fixture(scope="session")
def axe_js() -> str:
    """axe-core's source, for every test that audits a page (``tests/test_browser_a11y.py``'s ``load_axe``)."""
    from test_browser_a11y import load_axe

    return load_axe()


@pytest.fixture(scope="session")
def browser() -> Iterator[Any]:
    """Debian's Chromium, headless, driven by Playwright (a ``Browser``)."""
    if not Path(CHROMIUM).exists():
        skip_or_fail(f"{CHROMIUM} is missing: run `make browser-deps` (apt-get install chromium)")
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        skip_or_fail("playwright (python) is not installed: run `make setup-dev`")
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        yield browser
        browser.close()


@pytest.fixture
def views() -> Iterator[list[Any]]:
    """Kernel views (``Explorer.interactive()``) a test makes, closed after it (their worker threads end)."""
    made: list[Any] = []
    yield made
    for v in made:
        v.close()
        v._thread.join(10)
        assert not v._thread.is_alive()
