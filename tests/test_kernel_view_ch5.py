"""The Chapter 5 explorers' kernel views (``.interactive()``, what ``make lab`` shows), without a browser.

As in the page (tests/test_browser_live_ch5.py, the same moves): every control redraws the
figure; on the 2-D LQG the authors' switch selects their N_max; on the cart-pole, the thesis's
text leaves theta frozen and says so, and the authors' preset, one click, moves it. Here safepg
computes, in the view's worker thread.
"""

from __future__ import annotations

import html
from typing import Any

import pytest
from ch5_node import CH5_MOVES

from conftest import import_or_fail

import_or_fail("ipywidgets")

#: Seconds a computation may take on the shared 2-core machine (numba compiles on first use).
WAIT = 600


def explorer(name: str) -> Any:
    from safepg.thesis.explorers.cartpole_learner import cartpole_explorer
    from safepg.thesis.explorers.lqg2d_learner import lqg2d_adaptive_explorer, lqg2d_steps_explorer

    return {"steps": lqg2d_steps_explorer, "adaptive": lqg2d_adaptive_explorer, "cartpole": cartpole_explorer}[name]()


def drawn(view: Any) -> None:
    assert view.wait(WAIT), view.status.value
    assert view.error.value == "", view.error.value
    assert view.drawn == view.values()


@pytest.mark.parametrize("name", ["steps", "adaptive", "cartpole"])
def test_every_control_redraws(views, name):
    ex = explorer(name)
    view = ex.interactive()
    views.append(view)
    drawn(view)
    for control, value in CH5_MOVES[name]:
        before = view.figure.value
        view.controls[control].value = value
        drawn(view)
        assert view.drawn[control] == value
        assert view.figure.value != before, f"{control} did not change the figure"
    assert view.counts["failed"] == 0


def test_the_authors_switch_selects_their_n_max(views):
    ex = explorer("adaptive")
    view = ex.interactive()
    views.append(view)
    for on, n_max in ((True, "100000"), (False, "500000")):
        view.controls["authors"].value = on
        assert view.values()["n_max"] == n_max == ex.linked("authors", on)["n_max"]
    view.controls["budget"].value = "30000"
    view.controls["authors"].value = True
    drawn(view)
    assert view.drawn["n_max"] == "100000" and "(authors' settings)" in html.unescape(view.text.value)


def test_cartpole_presets_freeze_and_move_theta(views):
    view = explorer("cartpole").interactive()
    views.append(view)
    view.controls["budget"].value = "10000"
    buttons = {b.description: b for box in view.children for b in getattr(box, "children", ())
               if hasattr(b, "on_click")}
    buttons["the thesis's text"].click()
    drawn(view)
    assert "theta did not move: " in html.unescape(view.text.value)
    buttons["the authors' settings"].click()
    drawn(view)
    assert view.drawn["start"] == "theta_star" and "theta moved: " in html.unescape(view.text.value)
