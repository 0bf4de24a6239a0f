"""The settings audit's data and the safety measurement's closed-form count."""

import numpy as np
import pytest

from safepg import safety
from safepg.envs.lqg import LQG
from safepg.learning import vanilla_pg
from safepg.options import ErrorModel, FixedStep
from safepg.thesis import audit
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
    rec = vanilla_pg(LQG.thesis_1d(), np.array([-0.3]), 1.0, batch_size=100, step=FixedStep(1e-3), budget=5000, rng=1)
    out = safety.closed_form_outcomes(rec)
    dJ = np.diff(rec.J)
    moved = np.diff(rec.theta[:, 0]) != 0
    assert out["updates"] == moved.sum() == 50
    assert out["lowered"] == int(np.sum(moved & (dJ < 0)))
    assert out["lowered"] + out["raised"] + out["undetermined"] == out["updates"] and out["undetermined"] == 0
    assert out["detection_floor"] == 0.0  # exact: nothing hides under a floor
    assert out["share_lowered"] == pytest.approx(out["lowered"] / 50)
    assert out["share_lowered_upper95"] == safety.clopper_pearson_upper(out["lowered"], 50)
    assert out["unguarded"] == 0  # a fixed step is never marked unsafe
    # A record whose J falls at every move: every update lowered it.
    rec.J = -np.arange(rec.J.size, dtype=float)
    low = safety.closed_form_outcomes(rec)
    assert (low["lowered"], low["raised"], low["share_lowered_upper95"], low["largest_drop"]) == (50, 0, 1.0, 1.0)
    rec.J[3] = np.nan
    with pytest.raises(ValueError, match="record.J"):
        safety.closed_form_outcomes(rec)


def test_closed_form_table_of_a_small_adaptive_lqg_run():
    """An adaptive run on the 1-D LQG: its steps that did not move theta are no updates."""
    from safepg import adaptive_pg

    rec = adaptive_pg(LQG.thesis_1d(), np.array([-0.3]), 1.0, error=ErrorModel("chebyshev", 0.95), budget=60_000,
                      rng=2)
    out = safety.closed_form_outcomes(rec)
    moved = np.diff(rec.theta[:, 0]) != 0
    assert out["updates"] == moved.sum() > 0
    assert out["lowered"] + out["raised"] + out["undetermined"] == out["updates"]
    assert out["lowered"] == int(np.sum(np.diff(rec.J)[moved] < 0))
    k = out["lowered"]
    assert out["share_lowered_upper95"] == safety.clopper_pearson_upper(k, out["updates"])
    assert out["share_lowered_upper95"] >= 1 - 0.05 ** (1 / out["updates"]) - 1e-15  # at least the k = 0 bound


def test_closed_form_summary_of_a_J_sequence():
    J = np.array([-10.0, -9.0, -9.5, -9.5, -8.0, -8.25])
    out = safety.closed_form_summary(J)
    # changes +1, -0.5, 0 (not a worsening: the thesis's improvement), +1.5, -0.25
    assert (out["updates"], out["lowered"], out["raised"], out["undetermined"]) == (5, 2, 3, 0)
    assert out["largest_drop"] == 0.5 and out["detection_floor"] == 0.0
    assert out["share_lowered_upper95"] == safety.clopper_pearson_upper(2, 5)
    assert safety.closed_form_summary(J, np.array([0, 3]))["lowered"] == 0
    with pytest.raises(ValueError, match="^updates"):
        safety.closed_form_summary(J, np.array([5]))
    with pytest.raises(ValueError, match="^J"):
        safety.closed_form_summary(np.array([[1.0, 2.0]]))


def test_theorem_assumptions_tell_the_thesis_text_from_the_authors_settings():
    text = {r["assumption"]: r["holds"] for r in safety.theorem_assumptions(ex.get_experiment("table-5.2").configs[0])}
    assert all(text.values()), text  # REINFORCE, Chebyshev: every assumption holds
    authors = safety.theorem_assumptions(ex.get_experiment("table-5.4-authors").configs[0])
    assert not any(r["holds"] for r in authors)
    with pytest.raises(ValueError, match="adaptive"):
        safety.theorem_assumptions(ex.get_experiment("table-5.1").configs[0])
