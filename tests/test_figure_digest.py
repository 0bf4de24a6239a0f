"""Figures under nbval: a figure's text form is the digest of what it plots (safepg/figure_digest.py).

nbval skips images and the sanitizer reduces a figure's text to ``<Figure>``, so a figure cell passes
whatever it draws. With ``plotting.use_style(digest=True)`` the text form of every figure is its
digest; the last tests run nbval, with the book's sanitizer, on a small notebook made here, and show
that changing one plotted value of its figure cell then fails nbval, where without the digest it passed.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import nbformat  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from safepg.figure_digest import figure_digest  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SANITIZER = ROOT / "tests" / "nbval_sanitize.cfg"


def drawn(y_last: float = 6.0, band_top: float = 7.0) -> Figure:
    """A figure with one of each kind of artist, two axes (the second a twin) and an inset axes."""
    fig = Figure(figsize=(6, 4))
    ax = fig.subplots()
    ax.plot([1, 2, 3], [4.0, 5.0, y_last], label="mean")
    ax.fill_between([1, 2, 3], [3.0, 4.0, 5.0], [5.0, 6.0, band_top], alpha=0.3)
    ax.scatter([1.5, 2.5], [4.5, 5.5], label="points")
    ax.bar([1, 2], [0.5, 0.25])
    ax.vlines([2.0], 0, 1)
    ax.annotate("N* = 500", (2, 5))
    ax.set_xlabel("trajectories")
    ax.set_xscale("log")
    twin = ax.twinx()
    twin.plot([1, 3], [np.nan, 2.0], label="_hidden")
    inset = ax.inset_axes([0.6, 0.6, 0.3, 0.3])
    inset.imshow(np.arange(6.0).reshape(2, 3))
    return fig


def _hash(text: str) -> str:
    return text.splitlines()[1].rsplit(" ", 1)[-1]


def test_the_digest_names_each_axes_and_artist_with_its_key_values() -> None:
    lines = figure_digest(drawn()).splitlines()
    assert lines[0] == "<Figure size 600x400 with 2 Axes>"  # matplotlib's own text (the inset is not counted)
    assert lines[1].startswith("plotted data to 4 significant digits, sha256 ") and len(_hash("\n".join(lines))) == 16
    assert lines[2] == "axes 1 (x: trajectories, log; y: -, linear): line ×1, band ×1, markers ×1, segments ×1, " \
                       "bar ×2, text ×1"
    assert '  line "mean": 3 points; x 1 to 3; y 4 to 6, last 6' in lines
    assert "  band: 9 points; x 1 to 3; y 3 to 7" in lines  # fill_between's outline, closed
    assert '  markers "points": 2 points; x 1.5 to 2.5; y 4.5 to 5.5' in lines
    assert "  bar: at x 0.6, height 0.5" in lines and "  bar: at x 1.6, height 0.25" in lines  # bars 0.8 wide
    assert '  text "N* = 500" at (2, 5)' in lines
    assert "  segments: 2 points; x 2; y 0 to 1" in lines
    assert "axes 1.1 (x: -, linear; y: -, linear): image ×1" in lines and "  image: 2x3 values, 0 to 5" in lines
    assert "axes 2 (x: -, log; y: -, linear): line ×1" in lines  # the twin, once
    assert lines[-1] == "  line: 2 points; x 1 to 3; y 2, last 2"  # a NaN is left out of the ranges; "_" labels unshown
    assert sum(line.startswith("axes ") for line in lines) == 3


def test_one_plotted_value_changes_the_hash_at_the_printed_precision_only() -> None:
    base = figure_digest(drawn())
    assert figure_digest(drawn()) == base  # the same figure, the same text
    # A change that shows at 4 significant digits changes the hash (and here the printed last value) ...
    moved = figure_digest(drawn(y_last=6.01))
    assert _hash(moved) != _hash(base) and "last 6.01" in moved
    # ... also where no printed value shows it: the band's top, inside the printed range.
    assert _hash(figure_digest(drawn(band_top=6.999))) != _hash(base)
    # A change below the printed precision does not (the digest is not a hash of floating-point bits).
    assert figure_digest(drawn(y_last=6.0 + 1e-9)) == base


def test_use_style_registers_the_digest_only_when_asked_and_only_in_a_kernel() -> None:
    from safepg import figure_digest as fd
    from safepg.thesis import plotting

    plotting.use_style(digest=True)  # no IPython kernel here: nothing to register, and no error
    assert fd.digest_figures() is False


def test_use_style_silences_the_legend_placement_timer_and_nothing_else() -> None:
    """matplotlib warns when placing a legend at loc="best" took over a second of wall time: under load a
    figure cell then wrote to stderr and failed nbval (book/lqg1d.ipynb's Figure 5.1 overlays, once)."""
    import warnings

    from safepg.thesis import plotting

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        plotting.use_style()
        warnings.warn('Creating legend with loc="best" can be slow with large amounts of data.', UserWarning,
                      stacklevel=1)
        warnings.warn("another warning", UserWarning, stacklevel=1)
    assert [str(w.message) for w in caught] == ["another warning"]


# -------------------------------------------------------------------------- the proof under nbval
_SETUP = """import matplotlib.pyplot as plt
from safepg.thesis import plotting
plotting.use_style(digest={digest})"""
_FIGURE = """fig, ax = plt.subplots(figsize=(4, 3))
ax.plot([1, 2, 3], [4.0, {value}, 6.0], label="J")
ax.set_xlabel("trajectories")"""


def notebook(folder: Path, digest: bool) -> Path:
    """A two-cell notebook (imports, one figure cell) executed on the kernel ``python3``, outputs stored."""
    from nbclient import NotebookClient

    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(_SETUP.format(digest=digest)),
                nbformat.v4.new_code_cell(_FIGURE.format(value="5.0"))]
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    NotebookClient(nb, timeout=300, kernel_name="python3", resources={"metadata": {"path": str(folder)}}).execute()
    path = folder / "figure.ipynb"
    nbformat.write(nb, path)
    return path


def change_plotted_value(path: Path) -> None:
    """The figure cell's second y value 5.0 -> 5.5, its stored outputs kept (as an edit of the code would)."""
    nb = nbformat.read(path, as_version=4)
    nb.cells[1].source = _FIGURE.format(value="5.5")
    nbformat.write(nb, path)


def nbval(path: Path) -> subprocess.CompletedProcess:
    """nbval on one notebook, strict, with the book's sanitizer, in a folder of its own (no repository config)."""
    (path.parent / "pytest.ini").write_text("[pytest]\n")
    env = {k: v for k, v in os.environ.items() if k != "PYTEST_ADDOPTS"}
    # The kernel "python3" of the interpreter running the tests (the venv's), as the Makefile sets it up.
    env["JUPYTER_PATH"] = os.pathsep.join(p for p in (str(Path(sys.prefix) / "share" / "jupyter"),
                                                       env.get("JUPYTER_PATH")) if p)
    env["JUPYTER_PREFER_ENV_PATH"] = "1"
    return subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-q", "--nbval",
                           "--nbval-sanitize-with", str(SANITIZER), str(path)], cwd=path.parent, env=env,
                          capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="module")
def notebooks(tmp_path_factory: pytest.TempPathFactory) -> dict[bool, Path]:
    """The notebook executed with and without the digest, each in its own folder."""
    return {digest: notebook(tmp_path_factory.mktemp(f"digest-{digest}"), digest) for digest in (True, False)}


def test_the_stored_figure_output_carries_the_digest(notebooks: dict[bool, Path]) -> None:
    outputs = nbformat.read(notebooks[True], as_version=4).cells[1].outputs
    figure = next(o for o in outputs if "image/png" in o.get("data", {}))
    text = figure["data"]["text/plain"]
    assert text.startswith("<Figure size 400x300 with 1 Axes>\nplotted data to 4 significant digits, sha256 ")
    assert 'line "J": 3 points; x 1 to 3; y 4 to 6, last 6' in text
    plain = next(o for o in nbformat.read(notebooks[False], as_version=4).cells[1].outputs if "image/png" in o["data"])
    assert plain["data"]["text/plain"] == "<Figure size 400x300 with 1 Axes>"  # what nbval compared before


def test_nbval_fails_when_one_plotted_value_changes(notebooks: dict[bool, Path]) -> None:
    path = notebooks[True]
    same = nbval(path)
    assert same.returncode == 0, same.stdout + same.stderr  # rerun unchanged: the digest is reproduced
    change_plotted_value(path)
    changed = nbval(path)
    assert changed.returncode == 1 and "1 failed" in changed.stdout, changed.stdout + changed.stderr
    assert "last 6" in changed.stdout and "sha256" in changed.stdout  # nbval shows the digests it compared


def test_without_the_digest_nbval_passes_whatever_the_figure_draws(notebooks: dict[bool, Path]) -> None:
    """The negative control: the same change, with the figure's text only ``<Figure ...>``, passes nbval."""
    path = notebooks[False]
    change_plotted_value(path)
    proc = nbval(path)
    assert proc.returncode == 0 and "2 passed" in proc.stdout, proc.stdout + proc.stderr
