#!/usr/bin/env bash
# CI's second step (.ci/run, after `make test`): the release's tests, tests/test_dist.py and
# tests/test_browser_release.py, once more under Debian 12's own python3 (3.11.2), which the README
# supports, when .venv runs another Python version. They build the wheel and install it with this
# Python, and unpack the book's tarball (tests/conftest.py's extract_archive: tarfile's
# filter="data" is Python 3.11.4's, so 3.11.2 takes the checked fallback, which test_dist.py's
# test_extract_archive_* also exercise there).
#
# Usage: tools/test_debian_python.sh [PYTHON]   (default /usr/bin/python3; extra arguments go to pytest)
#
# Run after `make test`: it reuses what that installed and built (.venv's uv and its cache of
# wheels, Chromium, the book's execution cache and results/, so the book fixture executes no
# notebook). Nothing to do, exit 0, where PYTHON is missing or is .venv's Python version.
#
# .venv-debian/ (git-ignored) is made from PYTHON as tools/setup_venv.sh makes .venv, and reused
# while its inputs are unchanged: a venv with pip (test_dist.py's pip installs the wheel into a
# fresh venv), requirements.txt, safepg (editable), then requirements-dev.txt as `make setup-dev`
# installs it, by .venv's pinned uv; and its own Jupyter kernel "python3", which the root
# conftest.py requires to be the interpreter running the tests.
set -euo pipefail
cd "$(dirname "$0")/.."
python=${1:-/usr/bin/python3}
shift || true
venv="$(pwd)/.venv-debian"
vpy="$venv/bin/python"
uv="$(pwd)/.venv/bin/uv"
stamp="$venv/.safepg-setup"
say() { echo "test-debian-python: $*"; }
die() { echo "test-debian-python: $*" >&2; exit 1; }
base_of() {
  "$1" -c 'import os, sys; print(os.path.realpath(getattr(sys, "_base_executable", sys.executable)))' 2>/dev/null
}
version_of() { "$1" -c 'import platform; print(platform.python_version())' 2>/dev/null; }

if ! [ -x "$python" ]; then say "no $python: nothing to run"; exit 0; fi
[ -x .venv/bin/python ] && [ -x "$uv" ] || die ".venv (with uv) is missing: run \`make test\` first"
version=$(version_of "$python") || die "cannot run $python"
if [ "$version" = "$(version_of .venv/bin/python)" ]; then
  say "$python is Python $version, as .venv: \`make test\` ran these tests with it"
  exit 0
fi
base=$(base_of "$python")

if ! { [ -x "$vpy" ] && [ "$(base_of "$vpy")" = "$base" ]; }; then
  rm -rf "$venv"
  # Debian ships venv's ensurepip in python3.X-venv (tools/setup_venv.sh installs it the same way).
  if ! "$base" -c 'import ensurepip, venv' 2>/dev/null; then
    pkg="python${version%.*}-venv"
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
      say "installing Debian's $pkg"
      apt-get update -qq && apt-get install -y -qq "$pkg" >/dev/null
    else
      die "$base cannot create a virtual environment: install $pkg"
    fi
  fi
  say "creating .venv-debian from $base (Python $version)"
  "$base" -m venv "$venv"
fi

export UV_PYTHON_DOWNLOADS=never
uv_install() { "$uv" pip install --quiet --python "$vpy" --excludes requirements-excludes.txt "$@"; }
inputs=$( { cat requirements.txt requirements-dev.txt requirements-excludes.txt pyproject.toml
            grep '^__version__' safepg/__init__.py || true; "$uv" --version; echo "$base"; } | sha256sum | cut -d' ' -f1)
if [ "$(cat "$stamp" 2>/dev/null)" != "$inputs" ]; then
  rm -f "$stamp"
  start=$SECONDS
  uv_install -r requirements.txt
  uv_install --no-deps -e .
  uv_install -r requirements-dev.txt
  "$uv" pip uninstall --quiet --python "$vpy" -r requirements-excludes.txt
  "$vpy" -m ipykernel install --sys-prefix --name python3 >/dev/null
  echo "$inputs" > "$stamp"
  say "installed requirements.txt, safepg and requirements-dev.txt into .venv-debian in $((SECONDS - start)) s"
fi

# As the Makefile runs the tests: this venv's tools first on the PATH, its Jupyter kernel first.
export PATH="$venv/bin:$PATH" VIRTUAL_ENV="$venv" JUPYTER_PATH="$venv/share/jupyter" JUPYTER_PREFER_ENV_PATH=1
say "Python $("$vpy" -c 'import platform; print(platform.python_version())') ($base): tests/test_dist.py tests/test_browser_release.py"
"$vpy" -m pytest tests/test_dist.py tests/test_browser_release.py "$@"
