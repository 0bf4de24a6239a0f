"""How the book presents results: captioned tables, thesis numbering, the errata page,
figure axes. The browser test (test_browser_book.py) checks the built pages."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
import pytest  # noqa: E402
import sympy as sp  # noqa: E402
from script_module import load

from safepg.tables import markdown_table  # noqa: E402
from safepg.thesis.analysis import errata_markdown, with_labels  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def _thesis_numbers():
    return load("book/_ext/thesis_numbers.py")


def test_markdown_table_plain_and_captioned():
    rows = [{"a": 1, "b": 2.5}]
    cols = [("a", "a", ""), ("b", "b", ".2f")]
    plain = markdown_table(rows, cols)
    assert plain.splitlines() == ["| a | b |", "|---|---|", "| 1 | 2.50 |"]
    captioned = markdown_table(rows, cols, caption="Average performance, 5 seeds.", name="table-5-2")
    lines = captioned.splitlines()
    assert lines[0] == ":::{table} Average performance, 5 seeds."
    assert lines[1] == ":name: table-5-2"
    assert lines[3:6] == plain.splitlines() and lines[-1] == ":::"
    assert captioned._repr_markdown_() == str(captioned)


def test_markdown_table_escapes_pipes_in_headers_and_cells():
    md = markdown_table([{"a": "x|y"}], [("a", "mean |diff|", "")])
    assert md.splitlines()[0] == "| mean \\|diff\\| |"
    assert md.splitlines()[2] == "| x\\|y |"


def test_markdown_table_refuses_a_name_without_caption():
    with pytest.raises(ValueError, match="^name"):
        markdown_table([{"a": 1}], [("a", "a", "")], name="table-5-1")
    with pytest.raises(ValueError, match="^caption"):
        markdown_table([{"a": 1}], [("a", "a", "")], caption="two\nlines")


def test_with_labels_copies_rows():
    rows = [{"estimator": "gpomdp", "bound": "hoeffding", "empirical_range": True, "ours": 1.0}]
    out = with_labels(rows, ", range 1280")
    assert out[0]["estimator"] == "G(PO)MDP" and out[0]["bound"] == "Hoeffding (e.r.), range 1280"
    assert rows[0]["bound"] == "hoeffding"  # the input is left alone


def test_errata_markdown_blocks():
    x = sp.Symbol("x")
    entries = [SimpleNamespace(location="Section 4.3", explanation="Why.", printed=x**2, corrected=x**2 + 1,
                               affects_experiments="no", impact="None."),
               SimpleNamespace(location="Section 4.2", explanation="A reference.", printed="see Theorem 3.3",
                               corrected="see Theorem 4.2.3", affects_experiments="no", impact="None."),
               SimpleNamespace(location="Lemma A", explanation="Sign.", printed=r"a \ge b", corrected=r"a \le b",
                               affects_experiments="possibly", impact="Maybe.")]
    md = errata_markdown(entries)
    blocks = md.split("\n\n")
    # every formula is a display block of its own (a paragraph of its own), so it can scroll
    assert "$$\nx^{2}\n$$" in blocks and "$$\nx^{2} + 1\n$$" in blocks and "$$\n1\n$$" in blocks
    assert "> see Theorem 3.3" in blocks  # a sentence is quoted, not set as math
    assert "$$\na \\ge b\n$$" in blocks
    assert md.count("### ") == 3


@pytest.mark.parametrize("label, expected", [
    ("fig-5-3", ("figure", ("5", 3))), ("table-5-2", ("table", ("5", 2))), ("fig-4-1", ("figure", ("4", 1))),
    ("fig-s5-1", ("figure", ("S5", 1))), ("table-s2-10", ("table", ("S2", 10))), ("table-e-1", ("table", ("E", 1))),
    ("fig-5", None), ("figure-5-3", None), ("id1", None), ("fig--3", None),
])
def test_thesis_number_from_label(label, expected):
    assert _thesis_numbers().thesis_number(label) == expected


def test_renumbering_overrides_sphinx_counts():
    mod = _thesis_numbers()
    env = SimpleNamespace(toc_fignumbers={
        "book/lqg2d": {"figure": {"fig-5-5": (1,), "fig-5-6": (2,)}, "table": {"table-5-3": (1,)}},
        "book/cartpole": {"figure": {"fig-s5-1": (1,)}, "code-block": {"x": (1,)}},
    })
    mod._renumber(env)
    assert env.toc_fignumbers["book/lqg2d"]["figure"] == {"fig-5-5": ("5", 5), "fig-5-6": ("5", 6)}
    assert env.toc_fignumbers["book/lqg2d"]["table"] == {"table-5-3": ("5", 3)}
    assert env.toc_fignumbers["book/cartpole"]["figure"] == {"fig-s5-1": ("S5", 1)}
    assert env.toc_fignumbers["book/cartpole"]["code-block"] == {"x": (1,)}  # other kinds untouched


def test_an_unchanged_book_rewrites_no_page_for_its_numbers():
    """Sphinx rewrites the pages whose figure numbers changed since the last build: with the thesis's
    numbers, only a page whose labels changed counts, not every page with a figure at every build."""
    mod = _thesis_numbers()
    labels = {"book/lqg2d": ["fig-5-5", "fig-5-6"], "book/cartpole": ["fig-s5-1"]}

    def sphinx_running_numbers(self, env):  # what Sphinx's collector does: 1, 2, ... per page
        env.toc_fignumbers = {doc: {"figure": {lab: (i + 1,) for i, lab in enumerate(labs)}}
                              for doc, labs in labels.items()}
        return sorted(env.toc_fignumbers)

    assign = mod._thesis_figure_numbers(sphinx_running_numbers)
    env = SimpleNamespace(toc_fignumbers={})
    assert sorted(assign(None, env)) == ["book/cartpole", "book/lqg2d"]  # the first build
    assert assign(None, env) == []  # nothing changed
    labels["book/cartpole"] = ["fig-s5-2"]
    assert assign(None, env) == ["book/cartpole"]
    assert env.toc_fignumbers["book/cartpole"]["figure"] == {"fig-s5-2": ("S5", 2)}


def test_figure_4_1_tick_labels_do_not_overlap():
    """The symmetric-log axis of Figure 4.1 prints no crowded, overlapping labels around 0."""
    from safepg.bounds import ErrorBound
    from safepg.thesis.figures import figure_4_1

    fig = figure_4_1(3.5, ErrorBound(11.3, 357.0), 9753.0)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    ax = fig.axes[0]
    assert ax.get_title() == ""  # the book's caption says what it is
    for axis in (ax.yaxis, ax.xaxis):
        labels = [t for t in axis.get_ticklabels() if t.get_visible() and t.get_text()]
        boxes = [t.get_window_extent(renderer) for t in labels]
        texts = [t.get_text() for t in labels]
        assert len(set(texts)) == len(texts), texts
        for i in range(len(boxes)):
            for j in range(i + 1, len(boxes)):
                assert not boxes[i].overlaps(boxes[j]), (texts[i], texts[j])
    ticks = [v for v in ax.get_yticks() if ax.get_ylim()[0] <= v <= ax.get_ylim()[1]]
    assert min(ticks) == 0 and all(v >= 0 for v in ticks)


def test_preliminaries_figures_have_no_titles():
    from safepg.envs.lqg import LQG
    from safepg.thesis.figures import figure_estimator_variance, figure_gradient_estimates, figure_lqg_performance

    env = LQG.thesis_1d()
    ns = [10, 100]
    est = {"clipped": {"reinforce": np.ones((2, 3)), "gpomdp": np.zeros((2, 3))}}
    figs = [figure_lqg_performance(env, np.linspace(-1, 0, 20)),
            figure_gradient_estimates(ns, est, -3.87, -0.3),
            figure_estimator_variance(np.array([0.5, 1.0]), {"reinforce": np.array([2.0, 1.0]),
                                                              "gpomdp": np.array([1.0, 0.5])})]
    for fig in figs:
        assert all(ax.get_title() == "" for ax in fig.axes)
        assert fig.get_facecolor()[:3] == (1.0, 1.0, 1.0) or matplotlib.rcParams["figure.facecolor"] != "white"
