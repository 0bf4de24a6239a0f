# Two entry points (see README): `make book` and `make test`; `make lab` opens the book's
# notebooks in JupyterLab. Each installs what it needs
# into .venv/, this clone's virtual environment (tools/setup_venv.sh): nothing goes into the
# interpreter that creates it, which Debian's python3 refuses (PEP 668), and no other clone
# on the machine sees this clone's safepg. PYTHON is the interpreter that creates .venv.
PYTHON ?= python3
VBIN := $(CURDIR)/.venv/bin
VPY := $(VBIN)/python
# Workers of `make test` (pytest-xdist): one per core.
TEST_JOBS ?= auto

# Every recipe runs the venv's tools, and so do their subprocesses (pytest's, jupyter-book's):
# the venv's bin comes first on the PATH. Jupyter looks for kernels in the venv before
# anywhere else (JUPYTER_PATH is searched first), so the notebooks' kernel "python3" is the
# venv's, whatever ~/.local/share/jupyter holds; JUPYTER_PREFER_ENV_PATH also puts the venv
# before the user's folder for the other Jupyter data.
export PATH := $(VBIN):$(PATH)
export VIRTUAL_ENV := $(CURDIR)/.venv
export JUPYTER_PATH := $(CURDIR)/.venv/share/jupyter
export JUPYTER_PREFER_ENV_PATH := 1

.PHONY: setup setup-dev browser-deps node-deps lint test test-lib book book-assets bench lab wasm dist

# Creates .venv on first use (installing Debian's python3.X-venv as root if missing), reuses
# it while requirements.txt and pyproject.toml are unchanged.
setup:
	@PYTHON_GIVEN=$(if $(filter command line environment override,$(origin PYTHON)),1) bash tools/setup_venv.sh "$(PYTHON)"

# The tools of `make test`, `make dist` and `make wasm` alone (requirements-dev.txt: pytest, nbval, Playwright,
# ruff, ziglang, build, ...), on top of setup's venv, by setup's uv; installed again when that file or
# setup's own install changes.
setup-dev: setup
	@h=$$(cat requirements-dev.txt requirements-excludes.txt .venv/.safepg-setup | sha256sum | cut -d' ' -f1); \
	if [ "$$(cat .venv/.safepg-dev 2>/dev/null)" != "$$h" ]; then \
	  UV_PYTHON_DOWNLOADS=never $(VBIN)/uv pip install --quiet --python $(VPY) --excludes requirements-excludes.txt \
	    -r requirements-dev.txt \
	  && echo "$$h" > .venv/.safepg-dev \
	  && echo "setup-dev: installed requirements-dev.txt into .venv"; fi

# Debian's Chromium for the browser test (Playwright drives it; no browser download).
browser-deps:
	@command -v chromium >/dev/null 2>&1 || (apt-get update -qq && apt-get install -y -qq chromium chromium-driver >/dev/null)

# Debian's Node.js for the tests that run the page's JavaScript against safepg (marked `node`).
node-deps:
	@command -v node >/dev/null 2>&1 || (apt-get update -qq && apt-get install -y -qq nodejs >/dev/null)

# Lint (pyproject.toml's ruff rules) on the library, tests, benchmarks and the book's tools and extensions;
# notebooks are checked by nbval.
lint: setup-dev
	$(VPY) -m ruff check safepg tests benchmarks book/tools book/_ext
	$(VPY) -m mypy

# The book first, as `make book` builds it (its computations use every core), then the tests on every
# core (pytest-xdist; a test file's tests run in one worker, in order: nbval's cells need that). Chromium
# and Node.js come from Debian; a test that finds either missing fails under CI=true (tests/conftest.py).
test: setup setup-dev browser-deps node-deps lint book
	$(VPY) -m pytest -n $(TEST_JOBS) --dist loadfile

test-lib: setup setup-dev node-deps
	$(VPY) -m pytest tests -m "not browser"

# MathJax from the npm registry into book/_vendor (pages render math offline), and axe-core into
# _build/vendor for the accessibility test (never published).
book-assets:
	bash book/tools/vendor_assets.sh

# -W: warnings are errors (broken references, bad math); notebooks run through the cache.
# First `safepg run-book` computes into results/ what the chapters compute (their experiments,
# the Table 5.1 sweep, the safety measurements), on all cores as the notebooks do, with a
# progress bar per experiment (plain lines, one per ~30 s, when stdout is not a terminal);
# what is stored is one "stored" line each. The notebooks then only read results/: execute_pages.py
# executes them on every core into the execution cache, where jupyter-book finds them.
book: setup book-assets
	bash book/tools/cache_guard.sh
	$(VPY) -m safepg run-book
	$(VPY) book/tools/execute_pages.py
	$(VBIN)/jupyter-book build . -W -n --keep-going

# dist/: the sdist and the wheel (python -m build), the built book as safepg-book-<version>.tar.gz
# (deterministic) and SHA256SUMS over them (tools/dist.sh).
dist: setup-dev book
	bash tools/dist.sh

bench: setup
	$(VPY) benchmarks/bench_iteration.py

# The page learner's WebAssembly kernel of the 2-D LQG, from its C source (tools/build_wasm.py).
wasm: setup-dev
	$(VPY) tools/build_wasm.py

# JupyterLab on lab/, a git-ignored working copy of the book's chapters refreshed from book/
# without losing your edits (book/ is never written), with this clone's kernel, on 127.0.0.1
# with a random token (tools/lab.sh); LAB_PORT=8888 by default, LAB_ARGS go to `jupyter lab`.
lab: setup
	@bash tools/lab.sh $(LAB_ARGS)
