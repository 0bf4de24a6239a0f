"""The scorecard as files: counts per status, the CSV and JSON of every row and of each thesis table."""

from __future__ import annotations

import csv
import json
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from safepg.thesis.scorecard.rows import scorecard
from safepg.thesis.scorecard.rules import (
    AUTHORS_ERROR_STATUS,
    AUTHORS_STATUS,
    GROUPS,
    INCONCLUSIVE_STATUS,
    KIND_RULE,
    RELEVANCE,
    RULES,
    STATUS_RULE,
    STATUSES,
    VACUOUS_STATUS,
    Row,
)
from safepg.thesis.scorecard.verdicts import CORRECTION, FDR_LEVEL


def counts(rows: Iterable[Row]) -> dict[str, dict[str, int]]:
    """Number of rows per group and status (groups in :data:`GROUPS` order, plus ``"all"``)."""
    out: dict[str, dict[str, int]] = {}
    for r in rows:
        for g in (r.group, "all"):
            out.setdefault(g, dict.fromkeys(STATUSES, 0))[r.status] += 1
    order = [g for g in (*GROUPS, "all") if g in out]
    return {g: out[g] for g in order}


#: How a chapter's sentence names each status (:func:`counts_text`).
STATUS_PHRASES = {"reproduced": "reproduced", AUTHORS_STATUS: "reproduced only with the authors' unprinted settings",
                  AUTHORS_ERROR_STATUS: "reproduced only through an error in the authors' code",
                  VACUOUS_STATUS: "that agree without carrying information",
                  INCONCLUSIVE_STATUS: "inconclusive",
                  "differs (explained)": "that differ for a reason the book explains", "open": "open"}


def counts_text(rows: Sequence[Row]) -> str:
    """The rows' counts as the chapters say them: "12 printed results: 9 reproduced, 3 open" (statuses
    with no row left out), and the rows flagged as agreeing without information on one of our columns."""
    n = counts(rows).get("all", dict.fromkeys(STATUSES, 0))
    parts = [f"{n[s]} {STATUS_PHRASES[s]}" for s in STATUSES if n[s]]
    flagged = sum(bool(r.no_information) for r in rows)
    also = (f"; in {flagged} of them one of our columns agrees with the print without information"
            if flagged else "")
    return f"{sum(n.values())} printed results: {', '.join(parts)}{also}"


#: The short name of each status in :func:`headline_numbers`' keys (``n_<name>``).
STATUS_KEYS = {"reproduced": "reproduced", AUTHORS_STATUS: "authors_settings", AUTHORS_ERROR_STATUS: "authors_error",
               VACUOUS_STATUS: "no_information", INCONCLUSIVE_STATUS: "inconclusive",
               "differs (explained)": "explained", "open": "open"}


def headline_numbers(rows: Sequence[Row]) -> dict[str, float]:
    """The numbers the book's front page quotes, from the rows: ``n_rows`` and the rows per status
    (``n_`` and a name of :data:`STATUS_KEYS`); the cart-pole's rows (``n_cartpole``) and those among
    them reproduced only with the authors' settings (``n_cartpole_authors_settings``); and the 2-D
    :math:`J(\theta^*)`: printed (``j_star_printed``), the expectation (``j_star_expected``) and
    the ratio of the authors' code's value to the expectation (``j_star_ratio``)."""
    n = counts(rows).get("all", dict.fromkeys(STATUSES, 0))
    out: dict[str, float] = {"n_rows": sum(n.values()), **{f"n_{STATUS_KEYS[s]}": n[s] for s in STATUSES}}
    cartpole = [r for r in rows if r.group == "Section 5.3"]
    out["n_cartpole"] = len(cartpole)
    out["n_cartpole_authors_settings"] = sum(r.status == AUTHORS_STATUS for r in cartpole)
    j_star = next(r for r in rows if r.id == "section-5.2/J-star")
    printed, expected, theirs = j_star.thesis_value, j_star.ours_value, j_star.authors_value
    if printed is None or expected is None or theirs is None:
        raise TypeError(f"the row {j_star.id} must hold the printed, expected and authors' J(theta*), got "
                        f"{printed!r}, {expected!r} and {theirs!r}")
    out["j_star_printed"] = printed
    out["j_star_expected"] = expected
    out["j_star_ratio"] = theirs / expected
    return out


#: The glue keys of rows' statuses start with this (:func:`status_key`).
STATUS_PREFIX = "status__"


def status_key(row_id: str) -> str:
    """The glue key under which a chapter quotes a row's status: ``status__`` and the row's id with ``__`` for
    each ``/`` (``table-5.4/adaptive/upsilon`` -> ``status__table-5.4__adaptive__upsilon``)."""
    return STATUS_PREFIX + row_id.replace("/", "__")


def row_id_of(key: str) -> str:
    """The row id a :func:`status_key` names.

    Raises
    ------
    ValueError
        If ``key`` is not a status key.
    """
    if not key.startswith(STATUS_PREFIX):
        raise ValueError(f"key must start with {STATUS_PREFIX!r}, got {key!r}")
    return key[len(STATUS_PREFIX):].replace("__", "/")


def statuses(rows: Sequence[Row], row_ids: Iterable[str]) -> dict[str, str]:
    """The statuses of ``row_ids`` by :func:`status_key`, for a chapter to glue: its verdict words then come
    from the scorecard, never from its prose.

    Raises
    ------
    KeyError
        If a row id is not among ``rows``.
    """
    by_id = {r.id: r for r in rows}
    missing = [i for i in row_ids if i not in by_id]
    if missing:
        raise KeyError(f"no scorecard row {missing}")
    return {status_key(i): by_id[i].status for i in row_ids}


def family_numbers(rows: Sequence[Row]) -> dict[str, float]:
    """The family of tests the correction covers, in the numbers the scorecard page quotes: ``n_random`` (rows
    judged on runs), ``n_tests`` (their columns with a test), ``n_rejected``, ``level`` (the threshold a test
    not rejected faces, :math:`(R + 1)q/m`) and ``fdr`` (the false discovery rate, :math:`q`)."""
    random = [r for r in rows if r.test]
    states = [s for r in random for s in (r.state, r.authors_state) if s]
    levels = [r.level for r in random if r.level is not None and "rejected" not in (r.state, r.authors_state)]
    return {"n_random": len(random), "n_tests": len(states), "n_rejected": sum(s == "rejected" for s in states),
            "level": max(levels) if levels else float("nan"), "fdr": FDR_LEVEL}


#: Columns of the CSV files (``fields`` go to the table files as their own columns).
CSV_COLUMNS = ("id", "group", "quantity", "where", "kind", "thesis", "ours", "difference", "status", "judged_on",
               "rule", "test", "p_value", "authors_p_value", "level", "detectable", "relevance", "relevance_text",
               "seeds_needed", "authors_seeds_needed", "state", "authors_state", "verdict",
               "judged_interval_low", "judged_interval_high", "judged_interval_text", "judged_seeds",
               "explanation", "link", "thesis_value", "ours_value", "ours_ci95_low", "ours_ci95_high", "seeds",
               "authors", "authors_value", "authors_ci95_low", "authors_ci95_high", "authors_seeds",
               "authors_experiment", "authors_output", "authors_output_value", "authors_output_source", "slip")

#: The thesis's tables: file stem -> row-id prefix.
TABLES = {"table-5.1": "table-5.1/", "table-5.2": "table-5.2/", "table-5.3": "table-5.3/", "table-5.4": "table-5.4/"}


def _ends(interval: list[float] | None) -> tuple[float | None, float | None]:
    """An interval's low and high ends as the CSV holds them (None and None for no interval)."""
    if not interval:
        return None, None
    lo, hi = interval
    return lo, hi


def _flat(r: Row) -> dict[str, Any]:
    d = {k: getattr(r, k) for k in CSV_COLUMNS if hasattr(r, k)}
    lo, hi = _ends(r.ours_ci95)
    a_lo, a_hi = _ends(r.authors_ci95)
    j_lo, j_hi = _ends(r.judged_interval)
    d.update(ours_ci95_low=lo, ours_ci95_high=hi, authors_ci95_low=a_lo, authors_ci95_high=a_hi,
             judged_interval_low=j_lo, judged_interval_high=j_hi)
    return d


def _write_csv(path: Path, rows: Sequence[dict[str, Any]], columns: Sequence[str]) -> None:
    with path.open("w", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, fieldnames=list(columns), extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if r.get(k) is None else json.dumps(r[k]) if isinstance(r.get(k), list | dict)
                            else r[k]) for k in columns})


def write_scorecard(path_dir: Path | str, rows: Sequence[Row] | None = None, **kwargs: Any) -> dict[str, Path]:
    """Write the scorecard and each thesis table (ours, ours under the authors' settings and the
    authors' output beside the thesis's) as CSV and JSON.

    Parameters
    ----------
    path_dir : Path or str
        Folder to write into (created).
    rows : sequence of Row, optional
        Default: :func:`scorecard` called with ``kwargs``.

    Returns
    -------
    dict
        File name -> path: ``scorecard.csv``, ``scorecard.json``, and ``table-5.k.csv`` /
        ``table-5.k.json`` for k = 1..4.
    """
    rows = list(scorecard(**kwargs) if rows is None else rows)
    out_dir = Path(path_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    written: dict[str, Path] = {}
    meta = {"kinds": KIND_RULE, "rules": RULES, "status_rule": STATUS_RULE, "relevance": RELEVANCE,
            "correction": {"method": "Benjamini-Hochberg", "false_discovery_rate": FDR_LEVEL, "why": CORRECTION},
            "counts": counts(rows)}
    p = out_dir / "scorecard.json"
    p.write_text(json.dumps({**meta, "rows": [r.to_dict() for r in rows]}, indent=1, ensure_ascii=False) + "\n",
                 encoding="utf-8")
    written[p.name] = p
    p = out_dir / "scorecard.csv"
    _write_csv(p, [_flat(r) for r in rows], CSV_COLUMNS)
    written[p.name] = p
    for stem, prefix in TABLES.items():
        sel = [r for r in rows if r.id.startswith(prefix)]
        keys = list(dict.fromkeys(k for r in sel for k in r.fields))
        flat = [{**r.fields, **_flat(r)} for r in sel]
        cols = [*keys, "quantity", "kind", "thesis", "ours", "ours_ci95_low", "ours_ci95_high", "difference", "status",
                "judged_on", "test", "p_value", "authors_p_value", "level", "detectable", "relevance", "seeds_needed",
                "verdict", "judged_interval_low", "judged_interval_high", "judged_interval_text", "judged_seeds",
                "thesis_value", "ours_value", "seeds", "authors", "authors_value", "authors_ci95_low",
                "authors_ci95_high", "authors_seeds", "authors_experiment", "authors_output", "authors_output_value",
                "authors_output_source", "slip", "id", "link"]
        p = out_dir / f"{stem}.csv"
        _write_csv(p, flat, cols)
        written[p.name] = p
        p = out_dir / f"{stem}.json"
        p.write_text(json.dumps({"table": stem, "rows": [{k: d.get(k) for k in cols} for d in flat]}, indent=1,
                                ensure_ascii=False) + "\n", encoding="utf-8")
        written[p.name] = p
    return written


def read_scorecard_json(path: Path | str) -> list[Row]:
    """The rows of a ``scorecard.json`` written by :func:`write_scorecard`."""
    data = json.loads(Path(path).read_text(encoding="utf-8"))
    return [Row.from_dict(d) for d in data["rows"]]


def read_csv(path: Path | str) -> list[dict[str, str]]:
    """The rows of a CSV written by :func:`write_scorecard` (all values as strings)."""
    with Path(path).open(newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))
