"""The settings audit's data and the safety measurement's closed-form count."""

import numpy as np
import pytest

from safepg.envs.lqg import LQG
from safepg.learning import vanilla_pg
from safepg.thesis import audit, safety
from safepg.thesis import experiments as ex


def test_source_link_points_at_the_line_of_the_commit():
    assert audit.source_link("cartpole/cartpole.py@b9588b7:42") == (
        "[`cartpole/cartpole.py@b9588b7:42`](https://github.com/T3p/adaptive-batch-size/blob/b9588b7/"
        "cartpole/cartpole.py#L42)")
    assert audit.source_link("lqgnd/lqgnd.py@92ac378:226-227").endswith("lqgnd/lqgnd.py#L226-L227)")
    for bad in ("cartpole.py", "cartpole.py@main", "cartpole.py@b9588b7:x"):
        with pytest.raises(ValueError, match="source"):
            audit.source_link(bad)


@pytest.mark.parametrize("section", audit.SECTIONS)
def test_every_audit_row_is_complete(section):
    assert audit.audit(section), f"section {section} has no audit row"
    for row in audit.audit(section):
        assert all(getattr(row, f).strip() for f in ("setting", "thesis", "authors", "ours", "effect")), row
        assert row.sources, row.setting
        assert "|" not in "".join((row.setting, row.thesis, row.authors, row.ours, row.effect)).replace("\\|", "")


def test_unknown_section_is_refused():
    with pytest.raises(ValueError, match="section"):
        audit.audit("5.4")


def test_closed_form_outcomes_count_what_the_record_shows():
    rec = vanilla_pg(LQG.thesis_1d(), np.array([-0.3]), 1.0, batch_size=100, alpha=1e-3, budget=5000, rng=1)
    out = safety.closed_form_outcomes(rec)
    dJ = np.diff(rec.J)
    moved = np.diff(rec.theta[:, 0]) != 0
    assert out["updates"] == moved.sum() == 50
    assert out["lowered"] == int(np.sum(moved & (dJ < 0)))
    assert out["share_lowered"] == pytest.approx(out["lowered"] / 50)
    assert out["unguarded"] == 0  # a fixed step is never marked unsafe
    # A record whose J falls at every move: every update lowered it.
    rec.J = -np.arange(rec.J.size, dtype=float)
    assert safety.closed_form_outcomes(rec)["lowered"] == 50
    rec.J[3] = np.nan
    with pytest.raises(ValueError, match="record.J"):
        safety.closed_form_outcomes(rec)


def test_theorem_assumptions_tell_the_thesis_text_from_the_authors_settings():
    text = {r["assumption"]: r["holds"] for r in safety.theorem_assumptions(ex.get_experiment("table-5.2").configs[0])}
    assert all(text.values()), text  # REINFORCE, Chebyshev: every assumption holds
    authors = safety.theorem_assumptions(ex.get_experiment("table-5.4-authors").configs[0])
    assert not any(r["holds"] for r in authors)
    with pytest.raises(ValueError, match="adaptive"):
        safety.theorem_assumptions(ex.get_experiment("table-5.1").configs[0])
