"""`make setup` builds this clone's own virtual environment, and installs nothing elsewhere.

The slow tests take two fresh ``git clone``\\ s of this repository (its committed state, as
CI sees it) and run ``make setup`` in each with Debian's externally managed
``/usr/bin/python3``: the README's scenario, where ``pip install`` into that interpreter
fails with "externally-managed-environment". They check that each clone gets a working
``.venv`` importing its own ``safepg``, that nothing was installed into the system
interpreter or the user's Jupyter folder, that a second ``make setup`` installs nothing,
and that each clone's notebook kernel, started as Jupyter Book and nbval start it, imports
that clone's ``safepg`` even with a user-level kernel ``python3`` pointing at the other
clone. Without an externally managed ``/usr/bin/python3`` they are skipped, except under
``CI=true``, where they fail: CI machines are Debian 12, and the check must run there.

The fast tests run ``tools/setup_venv.sh`` on an interpreter without ``ensurepip``
(Debian's python3 without ``python3.X-venv``), with a stand-in ``apt-get``.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import pytest

from conftest import skip_or_fail

ROOT = Path(__file__).resolve().parents[1]
DEBIAN_PYTHON = Path("/usr/bin/python3")
#: Variables of the calling shell that would change what `make setup` does: an activated
#: venv, Jupyter's search path, an outer make's flags and variables (`make test PYTHON=...`
#: reaches an inner make through MAKEFLAGS), pip's override of PEP 668.
_NOT_INHERITED = ("VIRTUAL_ENV", "JUPYTER_PATH", "JUPYTER_PREFER_ENV_PATH", "JUPYTER_DATA_DIR", "PYTHON",
                  "PYTHONPATH", "PYTHONHOME", "MAKEFLAGS", "MFLAGS", "MAKELEVEL", "MAKEOVERRIDES",
                  "PIP_BREAK_SYSTEM_PACKAGES", "PIP_USER", "PIP_REQUIRE_VIRTUALENV")

#: Run by a clone's venv python: start the kernel "python3" as nbval and Jupyter Book do
#: (a KernelManager by name, in the notebook's folder) and print what it imports.
_KERNEL_PROBE = """
import json, sys
from jupyter_client.manager import start_new_kernel

km, kc = start_new_kernel(kernel_name="python3", startup_timeout=120, cwd=sys.argv[1])
out = []


def hook(msg):
    if msg["msg_type"] == "stream":
        out.append(msg["content"]["text"])


try:
    kc.execute_interactive("import safepg, sys; print(safepg.__file__); print(sys.executable)", timeout=120,
                           output_hook=hook)
finally:
    kc.stop_channels()
    km.shutdown_kernel(now=True)
safepg_file, executable = "".join(out).split()
print(json.dumps({"kernel": km.kernel_spec.resource_dir, "safepg": safepg_file, "python": executable}))
"""


def user_env(**extra: str) -> dict[str, str]:
    """A root shell on stock Debian: Debian's ``/usr/bin`` first on the PATH, no venv active."""
    env = {k: v for k, v in os.environ.items() if k not in _NOT_INHERITED}
    path = [p for p in env["PATH"].split(os.pathsep) if p and not p.rstrip("/").endswith("/.venv/bin")]
    env["PATH"] = os.pathsep.join(["/usr/bin", *path])
    env.update(extra)
    return env


def system_state() -> dict[str, object]:
    """What an install into Debian's python or the user's Jupyter folder would change.

    Files by name and size (and the kernels by content): another session's own install of
    a kernel with identical contents must not count.
    """
    pip_list = subprocess.run([str(DEBIAN_PYTHON), "-m", "pip", "list", "--format=freeze"], env=user_env(),
                              capture_output=True, text=True, check=True).stdout
    files: dict[str, object] = {}
    for pattern in ("/usr/local/lib/python3*", f"{Path.home()}/.local/lib/python3*", "/usr/local/share/jupyter",
                    f"{Path.home()}/.local/share/jupyter/kernels"):
        for folder in sorted(Path("/").glob(pattern.lstrip("/"))):
            files[str(folder)] = sorted(
                (str(p), p.read_text() if p.name == "kernel.json" else p.stat().st_size)
                for p in folder.rglob("*") if p.is_file() and "__pycache__" not in p.parts)
    return {"pip list": pip_list, "files": files}


@dataclass
class Clone:
    path: Path
    setup_seconds: float
    setup_output: str

    @property
    def python(self) -> Path:
        return self.path / ".venv" / "bin" / "python"

    def make(self, *args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess:
        return subprocess.run(["make", "-C", str(self.path), "--no-print-directory", *args],
                              env=env or user_env(), capture_output=True, text=True, timeout=1800)


def make_clone(dest: Path, *args: str) -> Clone:
    subprocess.run(["git", "clone", "--quiet", str(ROOT), str(dest)], check=True, timeout=300)
    clone = Clone(dest, 0.0, "")
    start = time.monotonic()
    proc = clone.make("setup", *args)
    clone.setup_seconds = time.monotonic() - start
    clone.setup_output = proc.stdout + proc.stderr
    assert proc.returncode == 0, clone.setup_output[-3000:]
    return clone


@pytest.fixture(scope="module")
def debian_clones(tmp_path_factory) -> dict[str, object]:
    """Two fresh clones, each set up with Debian's python: A by the PATH, B by PYTHON=."""
    managed = None
    if DEBIAN_PYTHON.exists():
        stdlib = subprocess.run([str(DEBIAN_PYTHON), "-c", "import sysconfig; print(sysconfig.get_path('stdlib'))"],
                                capture_output=True, text=True).stdout.strip()
        managed = Path(stdlib, "EXTERNALLY-MANAGED")
    if managed is None or not managed.exists():
        skip_or_fail(f"no externally managed {DEBIAN_PYTHON} (Debian 12's python3; apt-get install python3)")
    tmp = tmp_path_factory.mktemp("clones")
    before = system_state()
    a = make_clone(tmp / "a")  # `make setup` as the README says, Debian's python3 first on the PATH
    b = make_clone(tmp / "b", f"PYTHON={DEBIAN_PYTHON}")
    print(f"make setup from a fresh clone: {a.setup_seconds:.0f} s and {b.setup_seconds:.0f} s")
    return {"a": a, "b": b, "before": before, "after": system_state(), "tmp": tmp}


def imported_safepg(python: Path, cwd: Path) -> str:
    return subprocess.run([str(python), "-c", "import safepg; print(safepg.__file__)"], cwd=cwd, env=user_env(),
                          capture_output=True, text=True, check=True).stdout.strip()


@pytest.mark.slow
def test_make_setup_on_stock_debian_python(debian_clones):
    a, b = debian_clones["a"], debian_clones["b"]
    # The scenario is the real one: Debian's pip refuses to install into its python.
    refused = subprocess.run([str(DEBIAN_PYTHON), "-m", "pip", "install", "--dry-run", "--no-index", "six"],
                             env=user_env(), capture_output=True, text=True)
    assert refused.returncode != 0 and "externally-managed-environment" in refused.stderr
    for clone in (a, b):
        assert "setup: creating .venv from /usr/bin/python3" in clone.setup_output
        cfg = (clone.path / ".venv" / "pyvenv.cfg").read_text()
        assert "home = /usr/bin\n" in cfg and "include-system-site-packages = false" in cfg
        # From outside the clone, so that nothing is imported from the working directory.
        assert imported_safepg(clone.python, debian_clones["tmp"]) == str(clone.path / "safepg" / "__init__.py")
        # requirements-excludes.txt: JupyterLab's dependencies ask for it, the venv does without it.
        excluded = subprocess.run([str(clone.python), "-c", "import jsonschema, nbformat; import rfc3987_syntax"],
                                  env=user_env(), capture_output=True, text=True)
        assert "No module named 'rfc3987_syntax'" in excluded.stderr, excluded.stderr
        git_status = subprocess.run(["git", "-C", str(clone.path), "status", "--porcelain"], capture_output=True,
                                    text=True, check=True).stdout
        assert git_status == ""  # everything setup made is git-ignored
    # Nothing went into Debian's python, /usr/local, ~/.local or the user's Jupyter kernels.
    assert debian_clones["after"] == debian_clones["before"]


@pytest.mark.slow
def test_second_make_setup_installs_nothing(debian_clones):
    a = debian_clones["a"]
    site = a.path / ".venv" / "lib"
    def files() -> list[tuple[str, int]]:
        return sorted((str(p), p.stat().st_mtime_ns) for p in site.rglob("*")
                      if p.is_file() and "__pycache__" not in p.parts)

    listing = files()
    start = time.monotonic()
    proc = a.make("setup")
    seconds = time.monotonic() - start
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == "setup: .venv is up to date (requirements.txt, pyproject.toml and interpreter unchanged)\n"
    assert files() == listing
    # Reported, not limited: that it installed nothing is what the listing and the message above show.
    print(f"second make setup: {seconds:.2f} s (first {a.setup_seconds:.0f} s)")


def _decoy(folder: Path, python: Path) -> Path:
    """A user-level Jupyter folder whose kernel "python3" runs ``python``, as `ipykernel install --user` made it."""
    spec = folder / "kernels" / "python3"
    spec.mkdir(parents=True)
    (spec / "kernel.json").write_text(json.dumps({
        "argv": [str(python), "-m", "ipykernel_launcher", "-f", "{connection_file}"],
        "display_name": "Python 3 (another clone)", "language": "python"}))
    return folder


@pytest.mark.slow
def test_two_clones_each_kernel_imports_its_own_safepg(debian_clones):
    a, b, tmp = debian_clones["a"], debian_clones["b"], debian_clones["tmp"]
    probe = tmp / "kernel_probe.py"
    probe.write_text(_KERNEL_PROBE)
    for own, other in ((a, b), (b, a)):
        # The other clone's kernel registered user-wide (what `ipykernel install --user` did).
        decoy = str(_decoy(tmp / f"decoy-{own.path.name}", other.python))
        book = own.path / "book"

        def kernel(env: dict[str, str], *, own=own, book=book) -> dict[str, str]:
            out = subprocess.run([str(own.python), str(probe), str(book)], env=env, capture_output=True, text=True,
                                 timeout=300)
            assert out.returncode == 0, out.stderr[-3000:]
            return json.loads(out.stdout.splitlines()[-1])

        # 1. Under make, with the environment every target sets (a recipe added to the Makefile).
        recipe = f"kernel-probe: ; @$(VPY) {probe} {book}"
        out = subprocess.run(["make", "-s", "-C", str(own.path), f"--eval={recipe}", "kernel-probe"],
                             env=user_env(JUPYTER_DATA_DIR=decoy), capture_output=True, text=True, timeout=300)
        assert out.returncode == 0, out.stderr[-3000:]
        under_make = json.loads(out.stdout.splitlines()[-1])
        # 2. From the activated venv without make (jupyter-book or pytest typed by hand).
        activated = user_env(JUPYTER_DATA_DIR=decoy, VIRTUAL_ENV=str(own.path / ".venv"),
                             PATH=f"{own.path / '.venv' / 'bin'}{os.pathsep}{user_env()['PATH']}")
        by_hand = kernel(activated)
        for seen in (under_make, by_hand):
            assert seen["safepg"] == str(own.path / "safepg" / "__init__.py")
            assert seen["python"] == str(own.python)
            assert seen["kernel"] == str(own.path / ".venv" / "share" / "jupyter" / "kernels" / "python3")
        # The decoy is a real threat: told to prefer the user's folder, Jupyter runs the other clone.
        shadowed = kernel({**activated, "JUPYTER_PREFER_ENV_PATH": "0"})
        assert shadowed["safepg"] == str(other.path / "safepg" / "__init__.py")


# -------------------------------------------------------------------------- no venv module
def _script_copy(tmp_path: Path) -> tuple[Path, dict[str, str], Path]:
    """tools/setup_venv.sh in an empty clone-like folder, an interpreter without ensurepip, a stand-in apt-get."""
    (tmp_path / "tools").mkdir()
    for name in ("tools/setup_venv.sh", "requirements.txt", "requirements-excludes.txt", "pyproject.toml"):
        (tmp_path / name).write_bytes((ROOT / name).read_bytes())
    fake = tmp_path / "fake"
    fake.mkdir()
    (fake / "ensurepip.py").write_text("raise ImportError('Debian ships ensurepip in python3.X-venv')\n")
    log = tmp_path / "apt.log"
    apt = fake / "apt-get"
    apt.write_text(f'#!/bin/sh\necho "$@" >> {log}\ncase "$1" in update) exit 0;; *) exit 1;; esac\n')
    apt.chmod(0o755)
    env = user_env(PYTHONPATH=str(fake))
    env["PATH"] = f"{fake}{os.pathsep}{env['PATH']}"
    return tmp_path / "tools" / "setup_venv.sh", env, log


def test_without_ensurepip_debian_python_gets_python3_venv_from_apt(tmp_path):
    if not DEBIAN_PYTHON.exists() or os.geteuid() != 0:
        skip_or_fail(f"needs Debian's {DEBIAN_PYTHON} (apt-get install python3) and root for apt-get")
    script, env, log = _script_copy(tmp_path)
    proc = subprocess.run(["bash", str(script), str(DEBIAN_PYTHON)], env=env, capture_output=True, text=True,
                          timeout=120)
    version = subprocess.run([str(DEBIAN_PYTHON), "-c", "import sys; print('%d.%d' % sys.version_info[:2])"],
                             capture_output=True, text=True, check=True).stdout.strip()
    assert (f"cannot create a virtual environment: installing Debian's python{version}-venv"
            in proc.stdout), proc.stdout + proc.stderr
    assert log.read_text().splitlines() == ["update -qq", f"install -y -qq python{version}-venv"]
    assert proc.returncode != 0 and not (tmp_path / ".venv").exists()  # the stand-in installed nothing


def interpreter_outside_usr_bin(folder: Path, base: str | None = None) -> str:
    """``base`` (default: the real interpreter behind this venv) where it is outside ``/usr/bin``; else
    (Debian's, as in CI) a copy of it in ``folder``, which runs with Debian's standard library (the prefix
    compiled in) from a path the setup script does not take for Debian's."""
    base = base or os.path.realpath(getattr(sys, "_base_executable", sys.executable))
    if not base.startswith("/usr/bin/"):
        return base
    copy = folder / "bin" / Path(base).name
    copy.parent.mkdir(parents=True)
    shutil.copy2(base, copy)
    probe = subprocess.run([str(copy), "-c", "import os, sys; print(os.path.realpath(sys.executable))"],
                           capture_output=True, text=True, check=True)
    assert probe.stdout.strip() == str(copy), probe.stdout  # the script sees the copy's path, not /usr/bin's
    return str(copy)


def test_without_ensurepip_elsewhere_says_what_to_install(tmp_path):
    """An interpreter outside ``/usr/bin`` without ensurepip: the script says what to install and installs
    nothing (with Debian's, in CI, through a copy of it elsewhere)."""
    base = interpreter_outside_usr_bin(tmp_path / "python")
    script, env, log = _script_copy(tmp_path)
    proc = subprocess.run(["bash", str(script), base], env=env, capture_output=True, text=True, timeout=120)
    version = subprocess.run([base, "-c", "import sys; print('%d.%d' % sys.version_info[:2])"], capture_output=True,
                             text=True, check=True).stdout.strip()
    assert proc.returncode == 1 and proc.stdout == "" and not log.exists()
    assert proc.stderr == (f"setup: {base} cannot create a virtual environment (no ensurepip): install "
                           f"python{version}-venv (apt-get install python{version}-venv) or set PYTHON to another "
                           "Python >= 3.11\n")


def test_nbval_kernel_beside_other_workers_runs_numba_on_one_thread(request: pytest.FixtureRequest) -> None:
    """Under pytest-xdist, nbval's kernel is ``python3`` with numba on one thread (conftest.py)."""
    if not hasattr(request.config, "workerinput") or not request.config.option.nbval:
        pytest.skip("only under pytest-xdist with nbval: alone, the notebooks keep every core")
    from jupyter_client.kernelspec import KernelSpecManager
    from jupyter_client.manager import start_new_kernel

    name = request.config.option.nbval_kernel_name
    assert name and name != "python3"
    assert KernelSpecManager().get_kernel_spec(name).argv == KernelSpecManager().get_kernel_spec("python3").argv
    km, kc = start_new_kernel(kernel_name=name, startup_timeout=120, cwd=str(ROOT / "book"))
    out: list[str] = []
    try:
        kc.execute_interactive("import numba, sys; print(numba.config.NUMBA_NUM_THREADS, sys.executable)",
                               timeout=120, output_hook=lambda msg: msg["msg_type"] == "stream"
                               and out.append(msg["content"]["text"]))
    finally:
        kc.stop_channels()
        km.shutdown_kernel(now=True)
    threads, executable = "".join(out).split()
    assert threads == "1"
    assert Path(executable).resolve().parent == Path(sys.executable).resolve().parent
