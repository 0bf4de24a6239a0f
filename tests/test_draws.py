"""The second draw's comparison: which rows it counts as changed, as moving between reproduced and not,
and as inconclusive; the guard on a folder of another draw; and ``two-draws --json``, whose standard
output is the comparison alone."""

from __future__ import annotations

import io
import json
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from safepg import cli
from safepg.thesis import draws
from safepg.thesis.experiment_store import Campaign, write_campaign
from safepg.thesis.scorecard.rules import AUTHORS_STATUS, INCONCLUSIVE_STATUS

REPRODUCED, DIFFERS, OPEN = "reproduced", "differs (explained)", "open"


def row(id: str, status: str, kind: str = "one run", p: float | None = 0.5) -> Any:
    return SimpleNamespace(id=id, status=status, kind=kind, p_value=p, authors_p_value=None)


FIRST = [row("a", REPRODUCED), row("b", REPRODUCED), row("c", DIFFERS), row("d", AUTHORS_STATUS),
         row("e", INCONCLUSIVE_STATUS), row("f", OPEN), row("exact", REPRODUCED, kind="closed form")]
SECOND = [row("a", REPRODUCED), row("b", DIFFERS, p=0.001), row("c", AUTHORS_STATUS), row("d", REPRODUCED),
          row("e", REPRODUCED), row("f", INCONCLUSIVE_STATUS), row("exact", OPEN, kind="closed form")]


def test_changes_flips_and_inconclusive_are_counted_on_the_random_rows() -> None:
    c = draws.compare_draws(FIRST, SECOND)
    assert [a.id for a, _ in c.rows] == ["a", "b", "c", "d", "e", "f"]  # the closed form is not random
    assert [a.id for a, _ in c.changed] == ["b", "c", "d", "e", "f"]
    # reproduced -> differs and differs -> the authors' form move; the rest change within a side or
    # to or from inconclusive
    assert [a.id for a, _ in c.flips] == ["b", "c"]
    assert c.inconclusive == (1, 1)
    text = draws.comparison_text(c)
    assert "5 of 6 random rows differ:" in text and "between reproduced (either form) and open or differs: 2" in text
    assert "  b: reproduced (p = 0.5) -> differs (explained) (p = 0.001)" in text


def test_the_draws_must_hold_the_same_rows() -> None:
    with pytest.raises(ValueError, match="random rows differ: \\['g'\\]"):
        draws.compare_draws(FIRST, [*SECOND, row("g", REPRODUCED)])


def test_a_folder_of_another_draw_is_refused(tmp_path: Path) -> None:
    write_campaign(Campaign(0, {"0123456789abcdef": 10}), tmp_path)  # the book's draw, seeds added
    with pytest.raises(ValueError, match="holds a campaign from seed 0, not 1000000"):
        draws.run_draw(tmp_path)
    write_campaign(Campaign(7, {}), tmp_path)
    with pytest.raises(ValueError, match="from seed 7"):
        draws.run_draw(tmp_path)


def test_two_draws_json_prints_only_the_comparison(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    def run_draw(root: Path, jobs: int = -1, stream: Any = None) -> None:
        print("two-draws: the experiments in 1 s", file=stream)

    by_root = {str(tmp_path): SECOND}
    monkeypatch.setattr(draws, "run_draw", run_draw)
    monkeypatch.setattr("safepg.thesis.scorecard.rows.build_rows", lambda root: by_root.get(str(root), FIRST))
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        assert cli.main(["two-draws", "--root", str(tmp_path), "--json"]) == 0
    got = json.loads(out.getvalue())
    assert got["changed"] == ["b", "c", "d", "e", "f"] and got["flips"] == ["b", "c"]
    assert got["inconclusive"] == [1, 1] and len(got["rows"]) == 6
    assert "two-draws: the experiments in 1 s" in err.getvalue()
    out = io.StringIO()
    with redirect_stdout(out), redirect_stderr(io.StringIO()):
        assert cli.main(["two-draws", "--root", str(tmp_path)]) == 0
    assert out.getvalue().startswith("two-draws: the experiments in 1 s\nrow | draw 1 | draw 2\n")
