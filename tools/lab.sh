#!/usr/bin/env bash
# `make lab`: JupyterLab on the book's notebooks (book/), to explore the explorers in a live
# kernel. Run after `make setup` (the Makefile does); any extra arguments go to `jupyter lab`.
#
# Usage: tools/lab.sh [jupyter lab options...]   (LAB_PORT: the port, default 8888)
#
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
c.ServerApp.root_dir = "$root/book"
c.ServerApp.open_browser = $open
c.ServerApp.allow_root = $allow_root
c.IdentityProvider.token = "$token"
EOF
echo "lab: JupyterLab on $root/book with the kernel of $venv (Ctrl-C twice stops it); open"
echo "lab:   http://127.0.0.1:$port/lab?token=$token"
"$venv/bin/jupyter-lab" --config="$cfg" "$@"
