#!/usr/bin/env bash
# `make setup`: this clone's virtual environment, .venv/, with requirements.txt, safepg
# (editable, from this clone) and the Jupyter kernel "python3" of this venv.
#
# Usage: tools/setup_venv.sh PYTHON   (the interpreter that creates .venv; with PYTHON_GIVEN=1,
# as `make setup PYTHON=...` sets, an existing .venv of another interpreter is made anew;
# SAFEPG_VENV=.venv-debian makes that folder instead, as tools/test_debian_python.sh does)
#
# Why a venv: nothing is installed into the interpreter that creates it. Debian's and
# Ubuntu's python3 (also Fedora's, Homebrew's) refuse `pip install` (PEP 668,
# "externally-managed-environment"), and an editable install into one shared interpreter
# re-points every other clone on the machine to this clone's safepg.
#
# Reused as it is when requirements.txt, pyproject.toml, the version and the interpreter are those of the
# last install (a stamp in the venv records their hash): a second `make book` installs
# nothing. The venv is made anew when PYTHON names another interpreter than the one it was
# made from, or when it no longer runs (its interpreter was removed).
set -euo pipefail
cd "$(dirname "$0")/.."
python=${1:?usage: tools/setup_venv.sh PYTHON}
venv="$(pwd)/${SAFEPG_VENV:-.venv}"
name=${venv##*/}
vpy="$venv/bin/python"
stamp="$venv/.safepg-setup"
say() { echo "setup: $*"; }
die() { echo "setup: $*" >&2; exit 1; }

# PYTHON=python3 must not find this venv's own python3 (make puts .venv/bin first on the PATH).
PATH=$(printf '%s' "$PATH" | tr ':' '\n' | { grep -vxF "$venv/bin" || true; } | paste -sd: -)
# The real interpreter behind PYTHON, even when PYTHON is itself a venv's python.
base_of() {
  "$1" -c 'import os, sys; print(os.path.realpath(getattr(sys, "_base_executable", sys.executable)))' 2>/dev/null
}

if [ -x "$vpy" ] && current=$(base_of "$vpy"); then
  if [ "${PYTHON_GIVEN:-}" = 1 ]; then
    wanted=$(base_of "$python") || die "cannot run PYTHON=$python"
    if [ "$wanted" != "$current" ]; then
      say "PYTHON=$python is $wanted, $name was made from $current: making $name anew"
      rm -rf "$venv"
    fi
  fi
elif [ -e "$venv" ]; then
  say "$venv does not run (its interpreter is gone?): making it anew"
  rm -rf "$venv"
fi

if [ ! -x "$vpy" ]; then
  base=$(base_of "$python") || die "cannot run PYTHON=$python: install Python 3.11 or set PYTHON=/path/to/python3.11"
  version=$("$base" -c 'import sys; print("%d.%d" % sys.version_info[:2])')
  "$base" -c 'import sys; sys.exit(sys.version_info < (3, 11))' \
    || die "safepg needs Python >= 3.11, $base is $version: set PYTHON=/path/to/python3.11"
  # Debian and Ubuntu ship venv's ensurepip in python3.X-venv; install it as root (as
  # `make browser-deps` installs Chromium), else say what to install.
  if ! "$base" -c 'import ensurepip, venv' 2>/dev/null; then
    pkg="python$version-venv"
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1 && [ "${base%/*}" = /usr/bin ]; then
      say "$base cannot create a virtual environment: installing Debian's $pkg"
      apt-get update -qq && apt-get install -y -qq "$pkg" >/dev/null
    else
      die "$base cannot create a virtual environment (no ensurepip): install $pkg (apt-get install $pkg) or set PYTHON to another Python >= 3.11"
    fi
  fi
  say "creating $name from $base (Python $version)"
  "$base" -m venv "$venv"
fi

# The installer: uv, pinned, from PyPI into the venv by the venv's pip (seconds where pip takes
# over a minute: it resolves once and links from its cache). It only ever installs into this
# venv's interpreter, never one of its own (UV_PYTHON_DOWNLOADS=never, --python).
UV_PIN=uv==0.13.9
export UV_PYTHON_DOWNLOADS=never
# requirements-excludes.txt: what is never installed, even as a dependency (the file says why).
uv_install() { "$venv/bin/uv" pip install --quiet --python "$vpy" --excludes requirements-excludes.txt "$@"; }

# What the install depends on: the pins and exclusions, the package's metadata (its version is read from
# safepg/__init__.py), the installer and the venv's interpreter.
inputs=$( { cat requirements.txt requirements-excludes.txt pyproject.toml; grep '^__version__' safepg/__init__.py 2>/dev/null || true; \
            echo "$UV_PIN"; base_of "$vpy"; } | sha256sum | cut -d' ' -f1)
if [ "$(cat "$stamp" 2>/dev/null)" != "$inputs" ]; then
  rm -f "$stamp"  # an interrupted install is redone next time
  start=$SECONDS
  "$vpy" -m pip install --quiet --disable-pip-version-check "$UV_PIN"
  uv_install -r requirements.txt
  uv_install --no-deps -e .
  # A venv made before a package was excluded still holds it.
  "$venv/bin/uv" pip uninstall --quiet --python "$vpy" -r requirements-excludes.txt
  # The notebooks' kernel "python3", inside the venv (never --user: that one would be every
  # clone's). Jupyter run from the venv, or with the JUPYTER_PATH the Makefile sets, finds it
  # before any kernel of that name in ~/.local/share/jupyter.
  "$vpy" -m ipykernel install --sys-prefix --name python3 >/dev/null
  echo "$inputs" > "$stamp"
  say "installed requirements.txt and safepg into $name in $((SECONDS - start)) s"
else
  say "$name is up to date (requirements.txt, pyproject.toml and interpreter unchanged)"
fi

# The kernel Jupyter Book and nbval will start: refuse to go on if it is not this venv's,
# so that no notebook ever runs with another interpreter's (another clone's) safepg.
JUPYTER_PATH="$venv/share/jupyter" JUPYTER_PREFER_ENV_PATH=1 "$vpy" -c '
import sys
from jupyter_client.kernelspec import KernelSpecManager
spec = KernelSpecManager().get_kernel_spec("python3")
if spec.argv[0] != sys.executable:
    sys.exit(f"setup: the Jupyter kernel python3 runs {spec.argv[0]} ({spec.resource_dir}), not {sys.executable}")
'
