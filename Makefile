# Two entry points (see README): `make book` and `make test`. Each installs what it needs.
PYTHON ?= python3
PIP := $(PYTHON) -m pip

.PHONY: setup browser-deps lint test test-lib book book-assets bench

setup:
	$(PIP) install --quiet --disable-pip-version-check -r requirements.txt
	$(PIP) install --quiet --disable-pip-version-check --no-deps -e .
	$(PYTHON) -m ipykernel install --user --name python3 >/dev/null

# Debian's Chromium for the browser test (Playwright drives it; no browser download).
browser-deps:
	@command -v chromium >/dev/null 2>&1 || (apt-get update -qq && apt-get install -y -qq chromium chromium-driver >/dev/null)

# Lint (pyproject.toml's ruff rules) on the library, tests and benchmarks; notebooks are checked by nbval.
lint: setup
	$(PYTHON) -m ruff check safepg tests benchmarks

test: setup browser-deps lint
	$(PYTHON) -m pytest

test-lib: setup
	$(PYTHON) -m pytest tests -m "not browser"

# MathJax from the npm registry into book/_vendor: pages render math offline.
book-assets:
	bash book/tools/vendor_assets.sh

# -W: warnings are errors (broken references, bad math); notebooks run through the cache.
book: setup book-assets
	bash book/tools/cache_guard.sh
	jupyter-book build . -W -n --keep-going

bench: setup
	$(PYTHON) benchmarks/bench_iteration.py
