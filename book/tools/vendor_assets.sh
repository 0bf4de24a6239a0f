#!/usr/bin/env bash
# Fetch the pinned third-party JavaScript from the npm registry: MathJax 3 into
# book/_vendor (git-ignored), so the built pages render math with no CDN and no network,
# and axe-core into _build/vendor (git-ignored), the accessibility checker that
# tests/test_browser_a11y.py runs on every page. Idempotent; each tarball is checked
# against a pinned SHA-256, so every machine gets byte-identical files.
#
#   bash book/tools/vendor_assets.sh          # both (`make book-assets`)
#   bash book/tools/vendor_assets.sh axe      # axe-core only (the a11y test's fixture)
#
# Why fetched and not committed: the book needs tex-chtml-full.js and its woff-v2 fonts
# (about 1.7 MB), which would be committed vendor code with its own licence to track;
# the pinned version plus checksum makes the fetch as reproducible as a commit. The same
# holds for axe-core (axe.min.js, about 0.55 MB, MPL-2.0), which only the tests load: it
# goes under _build/, outside html_static_path, so it is never published with the book.
# Why MathJax only in the book: the explorers are plain text/html with inline JavaScript (see
# safepg/explorers/component.py), so the pages need neither require.js nor the ipywidgets HTML
# manager; book/_ext/no_widgets.py fails the build if a widget output ever appears.
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
root="$(cd "$here/.." && pwd)"
what="${1:-all}"

# fetch NAME VERSION SHA256 TMPDIR: the registry's tarball of NAME@VERSION into TMPDIR,
# checked against SHA256 and unpacked there (TMPDIR/package/...).
fetch() {
  local name="$1" version="$2" sha256="$3" tmp="$4"
  local tgz="$tmp/$name-$version.tgz"
  if command -v npm >/dev/null 2>&1; then
    (cd "$tmp" && npm pack --silent "$name@$version" >/dev/null)
  else  # the same tarball, straight from the registry
    python3 -c "import sys, urllib.request; urllib.request.urlretrieve(sys.argv[1], sys.argv[2])" \
      "https://registry.npmjs.org/$name/-/$name-$version.tgz" "$tgz"
  fi
  echo "$sha256  $tgz" | sha256sum --check --quiet
  tar xzf "$tgz" -C "$tmp"
}

tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

if [ "$what" = all ]; then
  dest="$here/_vendor/mathjax"
  version="3.2.2"
  sha256="1b9c0a1c44df864e915690558e72adb9cc5203360daefd385084ced3b6c64c09"
  if ! { [ -f "$dest/tex-chtml-full.js" ] && [ "$(cat "$dest/VERSION" 2>/dev/null)" = "$version $sha256" ]; }; then
    mkdir -p "$tmp/mathjax"
    fetch mathjax "$version" "$sha256" "$tmp/mathjax"
    rm -rf "$dest"
    mkdir -p "$dest/output/chtml/fonts"
    cp "$tmp/mathjax/package/es5/tex-chtml-full.js" "$tmp/mathjax/package/LICENSE" "$dest/"
    cp -r "$tmp/mathjax/package/es5/output/chtml/fonts/woff-v2" "$dest/output/chtml/fonts/"
    echo "$version $sha256" > "$dest/VERSION"
  fi
fi

if [ "$what" = all ] || [ "$what" = axe ]; then
  dest="$root/_build/vendor/axe-core"
  version="4.14.1"
  sha256="e6b0ce02b84d892e2e33e403485e7f3d6c29e2be6df65daf44d89ba564139745"
  if ! { [ -f "$dest/axe.min.js" ] && [ "$(cat "$dest/VERSION" 2>/dev/null)" = "$version $sha256" ]; }; then
    mkdir -p "$tmp/axe"
    fetch axe-core "$version" "$sha256" "$tmp/axe"
    rm -rf "$dest"
    mkdir -p "$dest"
    cp "$tmp/axe/package/axe.min.js" "$tmp/axe/package/LICENSE" "$dest/"
    echo "$version $sha256" > "$dest/VERSION"
  fi
fi
