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
# Run after `make test`: it reuses what that installed and built (uv's cache of
# wheels, Chromium, the book's execution cache and results/, so the book fixture executes no
# notebook). Nothing to do, exit 0, where PYTHON is missing or is .venv's Python version.
#
# .venv-debian/ (git-ignored) is made from PYTHON by tools/setup_venv.sh, as .venv is, and reused
# while its inputs are unchanged: requirements.txt, safepg (editable) and its own Jupyter kernel
# "python3" (the root conftest.py requires it to be the interpreter running the tests), then
# requirements-dev.txt as `make setup-dev` installs it.
set -euo pipefail
cd "$(dirname "$0")/.."
python=${1:-/usr/bin/python3}
shift || true
venv="$(pwd)/.venv-debian"
vpy="$venv/bin/python"
say() { echo "test-debian-python: $*"; }
die() { echo "test-debian-python: $*" >&2; exit 1; }
version_of() { "$1" -c 'import platform; print(platform.python_version())' 2>/dev/null; }

if ! [ -x "$python" ]; then say "no $python: nothing to run"; exit 0; fi
[ -x .venv/bin/python ] || die ".venv is missing: run \`make test\` first"
version=$(version_of "$python") || die "cannot run $python"
if [ "$version" = "$(version_of .venv/bin/python)" ]; then
  say "$python is Python $version, as .venv: \`make test\` ran these tests with it"
  exit 0
fi
# The venv as `make setup` makes .venv (tools/setup_venv.sh, into .venv-debian), then
# requirements-dev.txt as `make setup-dev` installs it, each stamped and reused while unchanged.
SAFEPG_VENV=.venv-debian PYTHON_GIVEN=1 bash tools/setup_venv.sh "$python"
dev=$(cat requirements-dev.txt requirements-excludes.txt "$venv/.safepg-setup" | sha256sum | cut -d' ' -f1)
if [ "$(cat "$venv/.safepg-dev" 2>/dev/null)" != "$dev" ]; then
  UV_PYTHON_DOWNLOADS=never "$venv/bin/uv" pip install --quiet --python "$vpy" --excludes requirements-excludes.txt \
    -r requirements-dev.txt
  echo "$dev" > "$venv/.safepg-dev"
  say "installed requirements-dev.txt into .venv-debian"
fi

# As the Makefile runs the tests: this venv's tools first on the PATH, its Jupyter kernel first.
export PATH="$venv/bin:$PATH" VIRTUAL_ENV="$venv" JUPYTER_PATH="$venv/share/jupyter" JUPYTER_PREFER_ENV_PATH=1
say "Python $(version_of "$vpy") ($python): tests/test_dist.py tests/test_browser_release.py"
"$vpy" -m pytest tests/test_dist.py tests/test_browser_release.py "$@"
