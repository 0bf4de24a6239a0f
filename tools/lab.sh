#!/usr/bin/env bash
# `make lab`: JupyterLab on a working copy of the book's chapters (lab/, git-ignored), to explore
# the explorers in a live kernel. Run after `make setup` (the Makefile does); any extra
# arguments go to `jupyter lab`.
#
# Usage: tools/lab.sh [jupyter lab options...]   (LAB_PORT: the port, default 8888; LAB_DIR: the
# copy, default lab/ of this clone, whose notebooks find the stored runs in ../results)
#
# - JupyterLab saves the notebooks it shows (every two minutes, and on Ctrl-S), and book/'s
#   outputs are what the nbval tests compare against: it serves lab/, never book/.
#   tools/lab_copy.py makes the copy (book/'s notebooks and intro.md, no plumbing) and
#   refreshes it on each run: a chapter you never edited follows book/, one you edited is kept
#   (and a notice says when book/ has a newer version).
# - SAFEPG_RESULTS points at this clone's results/, so the kernel's `python -m safepg` and
#   run_experiment without a root read the store the book filled.
# - JupyterLab's news popup ("get notified about official Jupyter news?") and update check
#   are off: overrides.d/safepg.json in the venv's app settings (users' own settings still win).
# - The kernel is this clone's .venv ("python3", registered inside the venv by `make setup`):
#   JUPYTER_PATH puts .venv/share/jupyter before every other kernel folder.
# - Only this machine can connect (127.0.0.1), and only with a random token, which the URL
#   printed first carries (JupyterLab's own log masks a token it did not make). The settings
#   are in a config file of this user's only (mktemp makes it 0600), not on the command
#   line, where `ps` shows the token to every user of the machine; given with --config, it
#   is read instead of the user's own jupyter_server_config.py, so a `token = ""` there
#   cannot turn the token off. It is removed when JupyterLab stops.
# - The browser opens only where there is a screen (DISPLAY, WAYLAND_DISPLAY, macOS): on a
#   machine without one, Python's webbrowser would start a text browser in this terminal.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
venv="$root/.venv"
[ -x "$venv/bin/jupyter-lab" ] || { echo "lab: $venv/bin/jupyter-lab is missing: run make setup" >&2; exit 1; }
export JUPYTER_PATH="$venv/share/jupyter" JUPYTER_PREFER_ENV_PATH=1
export SAFEPG_RESULTS="${SAFEPG_RESULTS:-$root/results}"

lab_dir=${LAB_DIR:-$root/lab}
"$venv/bin/python" "$root/tools/lab_copy.py" "$root/book" "$lab_dir"
lab_dir=$(cd "$lab_dir" && pwd)
# No news popup, no update check (JupyterLab 4 reads overrides.d/*.json in its app settings folder).
overrides="$venv/share/jupyter/lab/settings/overrides.d"
mkdir -p "$overrides"
echo '{"@jupyterlab/apputils-extension:notification": {"fetchNews": "false", "checkForUpdates": false}}' \
  > "$overrides/safepg.json"

port=${LAB_PORT:-8888}
case $port in '' | *[!0-9]*) echo "lab: LAB_PORT must be a port number, got '$port'" >&2; exit 1 ;; esac
open=False
if [ -n "${DISPLAY:-}${WAYLAND_DISPLAY:-}" ] || [ "$(uname)" = Darwin ]; then open=True; fi
# Jupyter refuses to run as root unless told; root is who runs `make` on the build machines.
allow_root=False
if [ "$(id -u)" = 0 ]; then allow_root=True; fi

cfg=$(mktemp "${TMPDIR:-/tmp}/safepg-lab-XXXXXX.py")
trap 'rm -f "$cfg"' EXIT
# A trapped signal waits for JupyterLab, which shuts its kernels down on SIGTERM and SIGHUP,
# then the EXIT trap removes the config file (an untrapped SIGTERM would kill this shell at once).
trap 'exit 143' TERM
trap 'exit 129' HUP
token=$("$venv/bin/python" -c 'import secrets; print(secrets.token_urlsafe(32))')
cat > "$cfg" <<EOF
c.ServerApp.ip = "127.0.0.1"
c.ServerApp.port = $port
# The URL printed below names this port: a port in use is an error, not a move to the next one.
c.ServerApp.port_retries = 0
c.ServerApp.root_dir = "$lab_dir"
c.ServerApp.open_browser = $open
c.ServerApp.allow_root = $allow_root
c.IdentityProvider.token = "$token"
EOF
echo "lab: JupyterLab on $lab_dir (a copy of book/'s chapters; book/ is never written) with the kernel of $venv (Ctrl-C twice stops it); open"
echo "lab:   http://127.0.0.1:$port/lab?token=$token"
"$venv/bin/jupyter-lab" --config="$cfg" "$@"
