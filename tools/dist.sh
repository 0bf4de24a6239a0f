#!/usr/bin/env bash
# `make dist`: what a release publishes, in one folder (dist/ unless OUT is given).
#
#   safepg-<version>.tar.gz               the library's sdist   (python -m build)
#   safepg-<version>-py3-none-any.whl     the library's wheel   (python -m build)
#   safepg-book-<version>.tar.gz          the built book, _build/html, as safepg-book-<version>/
#   SHA256SUMS                            sha256sum of each file above (`sha256sum -c SHA256SUMS`)
#
# Usage: tools/dist.sh [OUT]   (run by `make dist` after `make book`). It runs this clone's
# .venv/bin/python (with `build` from requirements-dev.txt: `make setup-dev`), or the `python` on
# the PATH where there is no .venv. The book must already be built: this script packs
# _build/html as it is and builds no page.
#
# The book's tarball is deterministic: entries sorted by name, every mtime the same
# (SOURCE_DATE_EPOCH, else the time of the last commit), owner and group 0, modes
# normalised, and gzip without name or time stamp (-n), so the same pages give the same bytes.
# SOURCE_DATE_EPOCH also fixes the timestamps inside the wheel.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-dist}
html=_build/html
if [ -x .venv/bin/python ]; then python=.venv/bin/python; else python=python; fi

[ -f "$html/index.html" ] || { echo "dist: $html/index.html is missing: build the book first (make book)" >&2; exit 1; }
version=$("$python" -c 'import safepg; print(safepg.__version__)')
if [ -z "${SOURCE_DATE_EPOCH:-}" ]; then
  SOURCE_DATE_EPOCH=$(git log -1 --format=%ct 2>/dev/null || echo 0)
fi
export SOURCE_DATE_EPOCH

rm -rf "$out"
mkdir -p "$out"
# The sdist, then the wheel built from the unpacked sdist (build's default): no stale build/ of
# this clone can add a file to the wheel, and a file missing from the sdist is missing from both.
log=$(mktemp)
"$python" -m build --outdir "$out" . >"$log" 2>&1 || { cat "$log" >&2; rm -f "$log"; exit 1; }
rm -f "$log"

book="safepg-book-$version"
LC_ALL=C tar --create --format=gnu --sort=name --mtime="@$SOURCE_DATE_EPOCH" \
  --owner=0 --group=0 --numeric-owner --mode='u+rwX,go+rX,go-w' \
  --directory=_build --transform="s,^html,$book," html \
  | gzip -n -9 >"$out/$book.tar.gz"

(cd "$out" && LC_ALL=C find . -maxdepth 1 -type f ! -name SHA256SUMS -printf '%f\n' | LC_ALL=C sort \
  | xargs -d '\n' sha256sum -- >SHA256SUMS)
echo "dist: safepg $version in $out/:"
(cd "$out" && for f in *; do echo "  $f ($(stat -c %s -- "$f") bytes)"; done)
