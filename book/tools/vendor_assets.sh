#!/usr/bin/env bash
# Fetch MathJax 3 from the npm registry into book/_vendor (git-ignored), so the built
# pages render math with no CDN and no network. Idempotent; the tarball is checked
# against a pinned SHA-256, so every machine serves byte-identical files.
#
# Why fetched and not committed: the book needs tex-chtml-full.js and its woff-v2 fonts
# (about 1.7 MB), which would be committed vendor code with its own licence to track;
# the pinned version plus checksum makes the fetch as reproducible as a commit.
# Why MathJax only: the explorers are plain text/html with inline JavaScript (see
# safepg/thesis/explorers/component.py), so the pages need neither require.js nor the ipywidgets HTML
# manager; book/_ext/no_widgets.py fails the build if a widget output ever appears.
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
dest="$here/_vendor/mathjax"
version="3.2.2"
sha256="1b9c0a1c44df864e915690558e72adb9cc5203360daefd385084ced3b6c64c09"
if [ -f "$dest/tex-chtml-full.js" ] && [ "$(cat "$dest/VERSION" 2>/dev/null)" = "$version $sha256" ]; then
  exit 0
fi
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
tgz="$tmp/mathjax-$version.tgz"
if command -v npm >/dev/null 2>&1; then
  (cd "$tmp" && npm pack --silent "mathjax@$version" >/dev/null)
else  # the same tarball, straight from the registry
  python3 -c "import sys, urllib.request; urllib.request.urlretrieve(sys.argv[1], sys.argv[2])" \
    "https://registry.npmjs.org/mathjax/-/mathjax-$version.tgz" "$tgz"
fi
echo "$sha256  $tgz" | sha256sum --check --quiet
tar xzf "$tgz" -C "$tmp"
rm -rf "$dest"
mkdir -p "$dest/output/chtml/fonts"
cp "$tmp/package/es5/tex-chtml-full.js" "$tmp/package/LICENSE" "$dest/"
cp -r "$tmp/package/es5/output/chtml/fonts/woff-v2" "$dest/output/chtml/fonts/"
echo "$version $sha256" > "$dest/VERSION"
