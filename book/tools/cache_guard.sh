#!/usr/bin/env bash
# Jupyter Book's execution cache is keyed on the notebooks' code only; clear it when
# the library changed since the last build, so no page shows stale safepg output.
# Sphinx re-reads only sources whose files changed, so its environment goes too:
# without that, unchanged notebooks would keep their old HTML (and outputs).
set -euo pipefail
cd "$(dirname "$0")/../.."
stamp=_build/.safepg-hash
# Every source file of the package, subpackages, their static JavaScript and CSS and the data files included.
now=$(find safepg -type f \( -name '*.py' -o -name '*.js' -o -name '*.css' -o -path '*/data/*' \) \
      -not -path '*/__pycache__/*' \
      | LC_ALL=C sort | xargs cat | sha256sum | cut -d' ' -f1)
if [ "$(cat "$stamp" 2>/dev/null)" != "$now" ]; then
  rm -rf _build/.jupyter_cache _build/.doctrees _build/jupyter_execute
  mkdir -p _build
  echo "$now" > "$stamp"
fi
