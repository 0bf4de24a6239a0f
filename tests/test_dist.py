"""What `make dist` publishes works where it is published.

The wheel (``test_wheel_*``): ``python -m build`` builds the sdist and, from it, the wheel, as
``make dist`` does, into a temporary folder. ``check-wheel-contents`` passes on it; it holds
every file of ``safepg/`` that git tracks (or would: untracked, not ignored) and nothing
else; installed into a fresh virtual environment outside the clone, with its dependencies
constrained by ``requirements.txt``, it runs the README's first ```python block that uses the
library alone (no ``safepg.thesis``), from a folder outside the clone, where ``import safepg``
can only find the installed wheel. A wheel with one module taken out fails these checks.

The site (``test_site_*``): ``tools/dist.sh`` (what ``make dist`` runs after ``make book``)
packs the book that the ``book`` fixture built; its tarball, unpacked in a temporary folder,
is checked as a complete site: ``sha256sum -c SHA256SUMS`` passes, every local ``href`` and
``src`` of every page (and every ``url(...)`` of its CSS) names a file of the site, and every
``#fragment`` names an ``id`` (or an ``<a name>``) of its target page. Links to other
schemes (http, https, mailto, data, javascript) are not followed; HTML files under
``_static/`` (the themes' Jinja templates, copied as they are) are not pages. Packing twice
gives the same bytes.

Unpacking (``test_extract_archive_*``): the tarballs are unpacked by ``conftest.extract_archive``,
``filter="data"`` where tarfile has it (Python 3.11.4 on) and the same checks member by member on
Debian 12's Python 3.11.2 (``tools/test_debian_python.sh`` runs this file there). Both ways, on any
Python, refuse each archive that the data filter refuses and unpack a site as it does.
"""

from __future__ import annotations

import ast
import hashlib
import importlib.util
import io
import json
import os
import posixpath
import re
import subprocess
import sys
import tarfile
import textwrap
import time
import zipfile
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest
from test_readme import README, python_blocks

import safepg
from conftest import extract_archive

ROOT = Path(__file__).resolve().parents[1]
REQUIREMENTS = ROOT / "requirements.txt"
DIST_SH = ROOT / "tools" / "dist.sh"
VERSION = safepg.__version__
#: The wheel's and the sdist's names for this version.
WHEEL = f"safepg-{VERSION}-py3-none-any.whl"
SDIST = f"safepg-{VERSION}.tar.gz"
BOOK_TARBALL = f"safepg-book-{VERSION}.tar.gz"
pytestmark = pytest.mark.slow


def _tool_env() -> dict[str, str]:
    """The environment for the build tools: this interpreter's venv first on the PATH."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    return env


def _needs_build_tools() -> None:
    missing = [m for m in ("build", "check_wheel_contents") if importlib.util.find_spec(m) is None]
    if missing:
        pytest.fail(f"{', '.join(missing)} not installed in {sys.prefix}: `make setup-dev` installs "
                    "requirements-dev.txt (`make test` does)")


# --- the wheel --------------------------------------------------------------------------------


def library_example() -> str:
    """The README's first ```python block, run by tests/test_readme.py, that imports safepg's
    library only (``safepg`` and its modules other than ``safepg.thesis``) and nothing else."""
    for block in python_blocks(README.read_text(encoding="utf-8")):
        if block.skip is not None:
            continue
        modules = []
        for node in ast.walk(ast.parse(block.code)):
            if isinstance(node, ast.Import):
                modules += [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                modules.append(node.module or "")
        if modules and all(m == "safepg" or (m.startswith("safepg.") and not m.startswith("safepg.thesis"))
                           for m in modules):
            return block.code
    raise AssertionError("README.md has no ```python block that imports safepg's library alone")


def expected_wheel_files() -> set[str]:
    """Every file under safepg/ that git tracks or would track (untracked, not ignored)."""
    out = subprocess.run(["git", "ls-files", "--cached", "--others", "--exclude-standard", "-z", "safepg"],
                         cwd=ROOT, capture_output=True, check=True).stdout.decode()
    return {p for p in out.split("\0") if p and (ROOT / p).is_file()}


def wheel_problems(wheel: Path, expected: set[str]) -> list[str]:
    """What is wrong with the wheel's package files: missing ones, extra ones, and its RECORD
    naming files it does not hold (or not naming files it holds)."""
    with zipfile.ZipFile(wheel) as zf:
        names = [n for n in zf.namelist() if not n.endswith("/")]
        info = next(n for n in names if n.endswith(".dist-info/RECORD"))
        record = {line.split(",")[0] for line in zf.read(info).decode().splitlines() if line}
    package = {n for n in names if not n.split("/", 1)[0].endswith(".dist-info")}
    problems = [f"missing from the wheel: {p}" for p in sorted(expected - package)]
    problems += [f"in the wheel but not in the clone: {p}" for p in sorted(package - expected)]
    problems += [f"RECORD names a file the wheel lacks: {p}" for p in sorted(record - set(names))]
    problems += [f"not in RECORD: {p}" for p in sorted(set(names) - record)]
    return problems


#: Run in the installed venv from a folder outside the clone: the README block, after checking
#: that ``safepg`` is the installed wheel of this version.
RUN_EXAMPLE = textwrap.dedent("""
    import importlib.metadata, sys, safepg
    assert safepg.__file__.startswith(sys.prefix), f"safepg imported from {safepg.__file__}, not the venv"
    assert importlib.metadata.version("safepg") == safepg.__version__ == sys.argv[2], (
        importlib.metadata.version("safepg"), safepg.__version__, sys.argv[2])
    code = open(sys.argv[1]).read()
    exec(compile(code, "README.md", "exec"), {"__name__": "__main__"})
    print("example ran:", safepg.__file__)
""")


@dataclass
class Installed:
    """A fresh venv outside the clone with the wheel installed."""

    wheel: Path
    python: Path
    seconds: dict[str, float] = field(default_factory=dict)


def _fresh_venv(path: Path) -> Path:
    """A venv without pip (the running pip installs into it with ``--python``: faster)."""
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(path)], check=True)
    return path / "bin" / "python"


def _pip_install(python: Path, *args: str) -> subprocess.CompletedProcess:
    # --no-compile: no .pyc written for numpy, scipy, sympy... (half the install's time); they
    # are compiled on import as usual.
    return subprocess.run([sys.executable, "-m", "pip", "--python", str(python), "install", "--quiet",
                           "--disable-pip-version-check", "--no-compile", *args],
                          capture_output=True, text=True, env=_tool_env())


def run_example(python: Path, workdir: Path) -> subprocess.CompletedProcess:
    """Run :func:`library_example` with ``python`` in ``workdir`` (outside the clone)."""
    workdir.mkdir(parents=True, exist_ok=True)
    (workdir / "example.py").write_text(library_example())
    (workdir / "run.py").write_text(RUN_EXAMPLE)
    env = {k: v for k, v in _tool_env().items() if k not in ("VIRTUAL_ENV",)}
    env.update(SAFEPG_RESULTS=str(workdir / "results"), MPLBACKEND="Agg")
    return subprocess.run([str(python), "run.py", "example.py", VERSION], cwd=workdir, env=env,
                          capture_output=True, text=True, timeout=900)


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The sdist and the wheel, built as `make dist` builds them; the folder."""
    _needs_build_tools()
    out = tmp_path_factory.mktemp("build")
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "build", "--outdir", str(out), str(ROOT)], cwd=ROOT,
                          capture_output=True, text=True, env=_tool_env())
    assert proc.returncode == 0, f"python -m build failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    print(f"python -m build (sdist, then the wheel from it): {time.perf_counter() - start:.1f} s")
    assert sorted(p.name for p in out.iterdir()) == sorted([SDIST, WHEEL])
    return out


@pytest.fixture(scope="module")
def installed(built: Path, tmp_path_factory: pytest.TempPathFactory) -> Installed:
    """The wheel in a fresh venv under a temporary folder, its dependencies pinned by requirements.txt."""
    tmp = tmp_path_factory.mktemp("venv")
    assert not tmp.is_relative_to(ROOT)
    start = time.perf_counter()
    python = _fresh_venv(tmp / "venv")
    proc = _pip_install(python, "--constraint", str(REQUIREMENTS), str(built / WHEEL))
    assert proc.returncode == 0, f"pip install of the wheel failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    seconds = {"venv and pip install": time.perf_counter() - start}
    print(f"fresh venv + pip install --constraint requirements.txt {WHEEL}: {seconds['venv and pip install']:.1f} s")
    return Installed(built / WHEEL, python, seconds)


def test_wheel_passes_check_wheel_contents(built: Path) -> None:
    proc = subprocess.run([sys.executable, "-m", "check_wheel_contents", str(built / WHEEL)],
                          capture_output=True, text=True, env=_tool_env())
    assert proc.returncode == 0, f"check-wheel-contents:\n{proc.stdout}{proc.stderr}"


def test_wheel_holds_every_file_of_the_package(built: Path) -> None:
    expected = expected_wheel_files()
    assert "safepg/__init__.py" in expected and len(expected) > 50
    assert not wheel_problems(built / WHEEL, expected), "\n".join(wheel_problems(built / WHEEL, expected))


def test_wheel_pins_agree_with_requirements(built: Path) -> None:
    """Every dependency the wheel declares is pinned in requirements.txt (so the constraint applies)."""
    with zipfile.ZipFile(built / WHEEL) as zf:
        meta = zf.read(next(n for n in zf.namelist() if n.endswith(".dist-info/METADATA"))).decode()
    declared = {re.split(r"[\s;<>=!~\[]", line.split(":", 1)[1].strip(), maxsplit=1)[0].lower()
                for line in meta.splitlines() if line.startswith("Requires-Dist:") and "extra ==" not in line}
    pinned = {line.split("==")[0].strip().lower() for line in REQUIREMENTS.read_text().splitlines()
              if "==" in line and not line.lstrip().startswith("#")}
    assert declared and declared <= pinned, f"not pinned in requirements.txt: {sorted(declared - pinned)}"


def test_installed_wheel_runs_the_readme_example(installed: Installed, tmp_path: Path) -> None:
    start = time.perf_counter()
    proc = run_example(installed.python, tmp_path / "outside")
    installed.seconds["example"] = time.perf_counter() - start
    print(f"README example in the installed wheel: {installed.seconds['example']:.1f} s")
    assert proc.returncode == 0, f"the README's library example failed with the installed wheel:\n{proc.stderr[-4000:]}"
    assert "example ran:" in proc.stdout


def _without(wheel: Path, member: str, out: Path) -> Path:
    """A copy of ``wheel`` (same name, in ``out``) without ``member``; RECORD left as it was."""
    out.mkdir(parents=True, exist_ok=True)
    damaged = out / wheel.name
    with zipfile.ZipFile(wheel) as src, zipfile.ZipFile(damaged, "w", zipfile.ZIP_DEFLATED) as dst:
        for item in src.infolist():
            if item.filename != member:
                dst.writestr(item, src.read(item.filename))
    return damaged


def test_a_wheel_missing_a_module_fails(installed: Installed, tmp_path: Path) -> None:
    """The checks above can fail: a wheel without ``safepg/meta.py`` is caught by the file
    comparison, and the README example fails with it installed."""
    damaged = _without(installed.wheel, "safepg/meta.py", tmp_path / "damaged")
    problems = wheel_problems(damaged, expected_wheel_files())
    assert "missing from the wheel: safepg/meta.py" in problems, problems
    # Installed without its dependencies into a venv of its own, which is then given the good venv's
    # packages after its own (a .pth line, written after the install: pip would otherwise see the
    # good safepg there and install nothing). Its own, damaged safepg comes first on sys.path.
    python = _fresh_venv(tmp_path / "venv")
    proc = _pip_install(python, "--no-deps", str(damaged))
    assert proc.returncode == 0, proc.stderr[-3000:]
    purelib = "import sysconfig; print(sysconfig.get_path('purelib'))"
    site, good = (subprocess.run([str(p), "-c", purelib], capture_output=True, text=True, check=True).stdout.strip()
                  for p in (python, installed.python))
    (Path(site) / "good_venv.pth").write_text(good + "\n")
    proc = run_example(python, tmp_path / "outside")
    assert proc.returncode != 0 and "No module named 'safepg.meta'" in proc.stderr, proc.stderr[-3000:]


# --- the site ---------------------------------------------------------------------------------


#: Attributes whose value is a URL, by tag (``None``: any tag).
URL_ATTRS = {"href": None, "src": None, "data": {"object"}, "poster": {"video"}}
#: Schemes that are not files of the site.
EXTERNAL = re.compile(r"^(?:[a-zA-Z][a-zA-Z0-9+.-]*:|//)")
CSS_URL = re.compile(r"""url\(\s*(['"]?)(?P<url>[^'")]+)\1\s*\)""")


class _Page(HTMLParser):
    """The ids and anchor names a page defines and the URLs it references, with their line."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.ids: set[str] = set()
        self.refs: list[tuple[int, str, str]] = []  # (line, attribute, url)

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        for name, value in attrs:
            if value is None:
                continue
            if name == "id" or (name == "name" and tag == "a"):
                self.ids.add(value)
            tags = URL_ATTRS.get(name, set())
            if name in URL_ATTRS and (tags is None or tag in tags):
                self.refs.append((self.getpos()[0], name, value))
            if name == "srcset":
                self.refs += [(self.getpos()[0], name, c.split()[0]) for c in value.split(",") if c.strip()]

    handle_startendtag = handle_starttag


@dataclass
class LinkReport:
    """What :func:`check_site` checked and what it found broken."""

    pages: int = 0
    links: int = 0  # local references to a file (href, src, CSS url())
    anchors: int = 0  # of those, the ones with a #fragment checked against their target page
    external: int = 0
    broken: list[str] = field(default_factory=list)


def check_site(root: Path) -> LinkReport:
    """Check every local link and anchor of the static site in ``root`` (see the module doc)."""
    root = root.resolve()
    report = LinkReport()
    parsed: dict[Path, _Page] = {}

    def page(path: Path) -> _Page:
        if path not in parsed:
            p = _Page()
            p.feed(path.read_text(encoding="utf-8", errors="replace"))
            p.close()
            parsed[path] = p
        return parsed[path]

    def check(source: Path, line: int, url: str, fragments: bool) -> None:
        url = url.strip()
        if not url or EXTERNAL.match(url):
            report.external += bool(url)
            return
        parts = urlsplit(url)
        where = f"{source.relative_to(root)}:{line}: {url}"
        if parts.path:
            target = Path(posixpath.normpath(posixpath.join(source.parent.as_posix(), unquote(parts.path))))
            if parts.path.endswith("/") or target.is_dir():
                target = target / "index.html"
        else:
            target = source
        report.links += 1
        if not target.is_relative_to(root):
            report.broken.append(f"{where} (outside the site)")
            return
        if not target.is_file():
            report.broken.append(f"{where} (no file {target.relative_to(root)})")
            return
        fragment = unquote(parts.fragment)
        if fragments and fragment and target.suffix == ".html":
            report.anchors += 1
            if fragment not in page(target).ids:
                report.broken.append(f"{where} (no id {fragment!r} in {target.relative_to(root)})")

    for path in sorted(root.rglob("*")):
        # _static/ holds the themes' and extensions' files copied as they are, among them two Jinja
        # templates named .html (webpack-macros.html) that no page links to: not pages.
        if path.suffix == ".html" and path.is_file() and path.relative_to(root).parts[0] != "_static":
            report.pages += 1
            for line, _attr, url in page(path).refs:
                check(path, line, url, fragments=True)
        elif path.suffix == ".css" and path.is_file():
            text = path.read_text(encoding="utf-8", errors="replace")
            for m in CSS_URL.finditer(text):
                check(path, text.count("\n", 0, m.start()) + 1, m["url"], fragments=False)
    return report


def test_link_checker_finds_broken_links(tmp_path: Path) -> None:
    """check_site on a small site: the good links pass, each kind of broken one is reported."""
    (tmp_path / "sub").mkdir()
    (tmp_path / "index.html").write_text(
        '<a href="sub/page.html#here">ok</a> <a href="#top" id="top">ok</a> <a href="sub/">ok</a>'
        '<img src="sub/pic%20one.png"> <a href="https://example.org/x#y">external</a> <a href="mailto:a@b">m</a>'
        '<a href="sub/page.html#nowhere">bad anchor</a> <a href="gone.html">bad file</a>'
        '<link rel="stylesheet" href="style.css"> <a href="../outside.html">outside</a>')
    (tmp_path / "sub" / "page.html").write_text('<h1 id="here">x</h1><a name="named"></a><a href="../index.html#top">'
                                                '</a><a href="#named"></a>')
    (tmp_path / "sub" / "index.html").write_text("<p>index</p>")
    (tmp_path / "sub" / "pic one.png").write_bytes(b"")
    (tmp_path / "style.css").write_text("a { background: url('sub/pic%20one.png') }\n"
                                        "b { background: url(missing.woff) }")
    report = check_site(tmp_path)
    assert report.pages == 3 and report.external == 2
    assert [b.split(" (")[0] for b in report.broken] == [
        "index.html:1: sub/page.html#nowhere", "index.html:1: gone.html", "index.html:1: ../outside.html",
        "style.css:2: missing.woff"], report.broken
    assert report.links == 12 and report.anchors == 5


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _pack(out: Path) -> subprocess.CompletedProcess:
    return subprocess.run(["bash", str(DIST_SH), str(out)], cwd=ROOT, capture_output=True, text=True,
                          env=_tool_env())


@pytest.fixture(scope="module")
def dist(book: Path, tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """tools/dist.sh (as `make dist` runs it) on the book fixture's build; its output folder."""
    _needs_build_tools()
    out = tmp_path_factory.mktemp("dist") / "dist"
    start = time.perf_counter()
    proc = _pack(out)
    assert proc.returncode == 0, f"tools/dist.sh failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    print(f"tools/dist.sh: {time.perf_counter() - start:.1f} s")
    yield out


def test_site_dist_holds_the_release(dist: Path) -> None:
    assert sorted(p.name for p in dist.iterdir()) == sorted([SDIST, WHEEL, BOOK_TARBALL, "SHA256SUMS"])
    sums = (dist / "SHA256SUMS").read_text().splitlines()
    assert sorted(line.split("  ", 1)[1] for line in sums) == sorted([SDIST, WHEEL, BOOK_TARBALL])
    proc = subprocess.run(["sha256sum", "--check", "--strict", "SHA256SUMS"], cwd=dist, capture_output=True,
                          text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_site_tarball_is_deterministic(dist: Path, tmp_path: Path) -> None:
    with tarfile.open(dist / BOOK_TARBALL) as tar:
        members = tar.getmembers()
    names = [m.name for m in members]
    assert names[0] == f"safepg-book-{VERSION}" and all(
        n == names[0] or n.startswith(names[0] + "/") for n in names), names[:5]
    assert {(m.uid, m.gid, m.uname, m.gname) for m in members} == {(0, 0, "", "")}
    assert len({m.mtime for m in members}) == 1
    assert (dist / BOOK_TARBALL).read_bytes()[4:8] == b"\0\0\0\0", "gzip header carries a time stamp"
    again = tmp_path / "again"
    proc = _pack(again)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert _sha256(again / BOOK_TARBALL) == _sha256(dist / BOOK_TARBALL), "packing twice gave other bytes"


def test_site_links_and_anchors_resolve(dist: Path, tmp_path: Path) -> None:
    with tarfile.open(dist / BOOK_TARBALL) as tar:
        extract_archive(tar, tmp_path)
    site = tmp_path / f"safepg-book-{VERSION}"
    assert (site / "index.html").is_file()
    start = time.perf_counter()
    report = check_site(site)
    summary = {"pages": report.pages, "links": report.links, "anchors": report.anchors,
               "external (not followed)": report.external, "broken": len(report.broken),
               "seconds": round(time.perf_counter() - start, 1)}
    print("link check of the unpacked book:", json.dumps(summary))
    assert report.pages > 5 and report.links > 100
    assert not report.broken, f"{len(report.broken)} broken links or anchors:\n" + "\n".join(report.broken)


# --- unpacking on Debian 12's Python 3.11.2 ---------------------------------------------------


def _entry(name: str, kind: bytes = tarfile.REGTYPE, data: bytes = b"", linkname: str = "",
           mode: int = 0o644) -> tuple[tarfile.TarInfo, bytes]:
    info = tarfile.TarInfo(name)
    info.type, info.linkname, info.mode, info.size, info.mtime = kind, linkname, mode, len(data), 1_700_000_000
    if kind == tarfile.CHRTYPE:
        info.devmajor, info.devminor = 1, 3
    return info, data


def _archive(path: Path, *entries: tuple[tarfile.TarInfo, bytes]) -> Path:
    with tarfile.open(path, "w") as tar:
        for info, data in entries:
            tar.addfile(info, io.BytesIO(data) if info.isreg() else None)
    return path


#: Archives that ``filter="data"`` refuses, by their destination folder; each aims at ``outside/`` beside it.
REFUSED: dict[str, Callable[[Path], list[tuple[tarfile.TarInfo, bytes]]]] = {
    "a name with ..": lambda dest: [_entry("../outside/evil.txt", data=b"x")],
    "a symlink out": lambda dest: [_entry("link", tarfile.SYMTYPE, linkname="../outside")],
    "a symlink deeper out": lambda dest: [_entry("a/b", tarfile.DIRTYPE, mode=0o755),
                                          _entry("a/b/link", tarfile.SYMTYPE, linkname="../../../outside/x")],
    "an absolute symlink": lambda dest: [_entry("link", tarfile.SYMTYPE, linkname="/etc/passwd")],
    "an absolute symlink into the folder": lambda dest: [_entry("link", tarfile.SYMTYPE, linkname=str(dest / "x"))],
    "a hard link out": lambda dest: [_entry("hard", tarfile.LNKTYPE, linkname="../outside/secret")],
    # Lexically here/../evil.txt is inside; through the symlink extracted first it is not.
    "a path through a symlink": lambda dest: [_entry("here", tarfile.SYMTYPE, linkname="."),
                                              _entry("here/../outside/evil.txt", data=b"x")],
    "a device": lambda dest: [_entry("null", tarfile.CHRTYPE)],
    "a pipe": lambda dest: [_entry("pipe", tarfile.FIFOTYPE)],
}


@pytest.fixture(params=["this interpreter", "fallback"])
def extraction(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> str:
    """``extract_archive`` as the running Python has it (``filter="data"`` from 3.11.4 on), and its
    fallback of Python 3.11.2 (Debian 12) on any Python: ``tarfile.data_filter`` taken away."""
    if request.param == "fallback":
        monkeypatch.delattr(tarfile, "data_filter", raising=False)
    return request.param


@pytest.mark.parametrize("case", REFUSED)
def test_extract_archive_refuses_what_the_data_filter_refuses(case: str, extraction: str, tmp_path: Path) -> None:
    (tmp_path / "outside").mkdir()
    (tmp_path / "outside" / "secret").write_text("secret")
    dest = tmp_path / "dest"
    path = _archive(tmp_path / "evil.tar", *REFUSED[case](dest))
    with tarfile.open(path) as tar, pytest.raises(tarfile.TarError):
        extract_archive(tar, dest)
    assert sorted(p.name for p in (tmp_path / "outside").iterdir()) == ["secret"]


def test_extract_archive_keeps_absolute_names_inside(extraction: str, tmp_path: Path) -> None:
    """An absolute name: the data filter extracts it under the destination (its ``/`` stripped), the
    fallback refuses it; neither writes where it points."""
    target = tmp_path / "outside" / "abs.txt"
    path = _archive(tmp_path / "abs.tar", _entry(str(target), data=b"x"))
    with tarfile.open(path) as tar:
        if hasattr(tarfile, "data_filter"):
            extract_archive(tar, tmp_path / "dest")
            assert (tmp_path / "dest" / str(target).lstrip("/")).read_bytes() == b"x"
        else:
            with pytest.raises(tarfile.TarError, match="absolute path"):
                extract_archive(tar, tmp_path / "dest")
    assert not target.exists()


def test_extract_archive_extracts_a_site(extraction: str, tmp_path: Path) -> None:
    """What the book's tarball holds (folders, files, links inside) comes out as the data filter gives
    it: contents, links, mtimes, and modes without setuid nor write for group and others (folders: the
    umask's, not the archive's)."""
    path = _archive(tmp_path / "site.tar",
                    _entry("site", tarfile.DIRTYPE, mode=0o755),
                    _entry("site/index.html", data=b"<p>home</p>", mode=0o666),
                    _entry("site/run.sh", data=b"#!/bin/sh\n", mode=0o4775),
                    _entry("site/_static", tarfile.DIRTYPE, mode=0o755),
                    _entry("site/_static/a.css", data=b"a {}", mode=0o400),
                    _entry("site/latest", tarfile.SYMTYPE, linkname="_static/a.css"),
                    _entry("site/copy.html", tarfile.LNKTYPE, linkname="site/index.html"))
    dest = tmp_path / "dest"
    with tarfile.open(path) as tar:
        extract_archive(tar, dest)
    site = dest / "site"
    assert sorted(p.relative_to(site).as_posix() for p in site.rglob("*")) == [
        "_static", "_static/a.css", "copy.html", "index.html", "latest", "run.sh"]
    assert (site / "index.html").read_bytes() == (site / "copy.html").read_bytes() == b"<p>home</p>"
    assert os.readlink(site / "latest") == "_static/a.css" and (site / "latest").read_bytes() == b"a {}"
    modes = {name: (site / name).stat().st_mode & 0o7777 for name in ("index.html", "run.sh", "_static/a.css")}
    assert modes == {"index.html": 0o644, "run.sh": 0o755, "_static/a.css": 0o600}
    assert (site / "run.sh").stat().st_mtime == 1_700_000_000
    umask = os.umask(0o022)
    os.umask(umask)
    assert {(site / d).stat().st_mode & 0o7777 for d in ("", "_static")} == {0o777 & ~umask}
