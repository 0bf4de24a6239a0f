"""A damaged results folder loses nothing and stops nothing.

Damaged means unreadable as a run: an empty, truncated or overwritten file, an archive
missing an array or its metadata, or arrays whose lengths do not form one run. ``run``
(and ``run_experiment``, which the book calls) sets such a file aside as
``seed-<k>.npz.damaged-<time>``, names it in one warning line and computes the run again;
``report`` names every damaged file and the ``run`` command that repairs it, and exits
with status 1. A readable file of other settings or another ``RESULTS_VERSION`` is stale,
not damaged: it is recomputed and overwritten without a word.
"""

import json
import os
import subprocess
import sys
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from test_runner_robustness import assert_same_records

from safepg import runner, store
from safepg.cli import main
from safepg.envs.lqg import LQG
from safepg.learning import LearningRecord, RecordFileError, adaptive_pg, vanilla_pg
from safepg.options import FixedStep
from safepg.thesis import experiment_store as es
from safepg.thesis import experiments as ex
from safepg.thesis import report as rp


def _record() -> LearningRecord:
    return vanilla_pg(LQG.thesis_1d(), np.array([-0.3]), 1.0, batch_size=100, step=FixedStep(1e-4), budget=1000, rng=0)


def _save_arrays(path: Path, rec: LearningRecord, **change) -> None:
    """``rec`` saved as :meth:`LearningRecord.save` does, with some arrays replaced (or None: left out)."""
    arrays = {k: getattr(rec, k) for k in ("batch_size", "alpha", "coordinate", "theta", "J", "J_hat", "grad",
                                           "eps", "safe")}
    arrays.update(change)
    meta = json.dumps({"config": rec.config, "interrupted": False})
    np.savez_compressed(path, meta=np.array(meta), **{k: v for k, v in arrays.items() if v is not None})


def _damage(path: Path, how: str) -> None:
    """Damage the run file ``path`` in one of the ways a results folder gets damaged."""
    good = path.read_bytes()
    rec = LearningRecord.load(path)
    if how == "truncated":  # a copy cut short (full disk, interrupted transfer)
        path.write_bytes(good[:1000])
    elif how == "garbage":  # overwritten with text
        path.write_text("this is not a run\n")
    elif how == "empty":
        path.write_bytes(b"")
    elif how == "bad crc":  # bytes flipped inside the archive
        path.write_bytes(good[:300] + bytes(b ^ 0xFF for b in good[300:400]) + good[400:])
    elif how == "bare npy":
        with open(path, "wb") as f:
            np.save(f, rec.theta)
    elif how == "missing array":
        _save_arrays(path, rec, grad=None)
    elif how == "wrong shape":  # one theta row too few for the iterations
        _save_arrays(path, rec, theta=rec.theta[:-1])
    elif how == "wrong dtype":
        _save_arrays(path, rec, safe=rec.safe.astype(float))
    elif how == "bad metadata":
        _save_arrays(path, rec)
        with np.load(path) as z:
            arrays = {k: z[k] for k in z.files}
        arrays["meta"] = np.array("{not json")
        np.savez_compressed(path, **arrays)
    else:
        raise ValueError(how)


DAMAGE = ["truncated", "garbage", "empty", "bad crc", "bare npy", "missing array", "wrong shape", "wrong dtype",
          "bad metadata"]


# -------------------------------------------------------------------------- what damaged means
def test_finished_runs_pass_the_check():
    for rec in (_record(), adaptive_pg(LQG.thesis_2d(), np.zeros(4), 1.0, budget=3000, rng=1)):
        rec.check()


@pytest.mark.parametrize("how", DAMAGE)
def test_a_damaged_file_is_a_record_file_error(tmp_path, how):
    path = tmp_path / "seed-0.npz"
    _record().save(path)
    _damage(path, how)
    with pytest.raises(RecordFileError) as info:
        LearningRecord.load(path)
    assert info.value.path == path and info.value.reason and str(path) in str(info.value)
    assert isinstance(info.value, ValueError)


def test_record_check_names_the_array_that_does_not_fit():
    rec = _record()
    for name, bad, message in (("grad", rec.grad[:-1], "grad must have shape (10, 1)"),
                               ("J", rec.J[:-1], "J must have shape (11,)"),
                               ("batch_size", rec.batch_size.astype(float), "batch_size must be an array of kind")):
        with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
            replace(rec, **{name: bad}).check()


def test_a_missing_file_or_folder_is_not_damage(tmp_path):
    with pytest.raises(FileNotFoundError):
        LearningRecord.load(tmp_path / "nothing.npz")
    (tmp_path / "dir.npz").mkdir()
    with pytest.raises(IsADirectoryError):
        LearningRecord.load(tmp_path / "dir.npz")
    assert store.load_stored(tmp_path / "nothing.npz", "key") is None


# -------------------------------------------------------------------------- the store
@pytest.fixture()
def root(tmp_path, monkeypatch):
    monkeypatch.setenv("SAFEPG_RESULTS", str(tmp_path))
    return tmp_path


def small(seeds=2):
    e = ex.get_experiment("table-5.2")
    return ex.scaled(replace(e, configs=e.configs[:2]), seeds, 3000)


def _files(exp):
    folder = es.experiment_folder(exp)
    return [runner.run_path(folder, c, k) for c in exp.configs for k in range(exp.seeds)]


def test_run_sets_damaged_files_aside_and_computes_them_again(root, tmp_path_factory):
    exp = small(seeds=3)
    clean = es.run_experiment(exp, jobs=1, progress=False, root=tmp_path_factory.mktemp("clean"))
    es.run_experiment(exp, jobs=1, progress=False)
    files = _files(exp)
    hows = ["truncated", "garbage", "empty", "wrong shape", "bad crc"]
    kept = {}
    for path, how in zip(files, hows):
        _damage(path, how)
        kept[path] = path.read_bytes()
    untouched = {p: p.stat().st_mtime_ns for p in files[len(hows):]}
    with pytest.warns(store.DamagedRunWarning) as caught:
        again = es.run_experiment(exp, jobs=1, progress=False)
    assert_same_records(clean, again)
    assert_same_records(clean, es.load_experiment(exp))
    assert len(caught) == len(hows)
    for path, w in zip(files, caught):
        (aside,) = path.parent.glob(f"{path.name}{store.DAMAGED_SUFFIX}*")
        assert aside.read_bytes() == kept[path]  # kept as it was, for inspection
        message = str(w.message)
        assert "\n" not in message and str(path) in message and aside.name in message
    assert all(p.stat().st_mtime_ns == t for p, t in untouched.items())
    # Set aside once: the next run reads everything and warns about nothing.
    with warnings.catch_warnings():
        warnings.simplefilter("error", store.DamagedRunWarning)
        es.run_experiment(exp, jobs=1, progress=False)


def test_readers_leave_damaged_files_out_and_in_place(root):
    exp = small()
    es.run_experiment(exp, jobs=1, progress=False)
    files = _files(exp)
    _damage(files[0], "truncated")
    _damage(files[3], "garbage")
    with pytest.warns(store.DamagedRunWarning, match="left out") as caught:
        recs = es.load_experiment(exp)
    assert [len(recs[c.name]) for c in exp.configs] == [1, 1] and len(caught) == 2
    with pytest.warns(store.DamagedRunWarning):
        rep = rp.report(exp)  # the book's read-only pages (the scorecard) go on too
    assert [r["seeds"] for r in rep["configs"]] == [1, 1]
    with pytest.raises(store.DamagedRunsError) as info:
        es.load_experiment(exp, on_damaged="raise")
    assert [d.path for d in info.value.damaged] == [files[0], files[3]]  # every one, not just the first
    assert not list(root.rglob(f"*{store.DAMAGED_SUFFIX}*"))


def test_stale_files_are_recomputed_silently(root, monkeypatch):
    """Another RESULTS_VERSION (or other settings) is not damage: the run is computed again into its own key's
    folder, the stale file stays where it was, nothing is set aside. The seeds do not follow the version
    (RunConfig.seed_key): with the same code the recomputed run has the stale one's bits."""
    exp = small(seeds=1)
    monkeypatch.setattr(runner, "RESULTS_VERSION", "0")
    old = es.run_experiment(exp, jobs=1, progress=False)
    old_keys = {c.name: c.key() for c in exp.configs}
    monkeypatch.undo()
    monkeypatch.setenv("SAFEPG_RESULTS", str(root))
    with warnings.catch_warnings():
        warnings.simplefilter("error", store.DamagedRunWarning)
        assert es.load_experiment(exp) == {c.name: [] for c in exp.configs}
        new = es.run_experiment(exp, jobs=1, progress=False)
    assert not list(root.rglob(f"*{store.DAMAGED_SUFFIX}*"))
    for c in exp.configs:
        assert len(new[c.name]) == 1 and c.key() != old_keys[c.name]
        assert new[c.name][0].config["run_key"] == c.key() and old[c.name][0].config["run_key"] == old_keys[c.name]
        stored_keys = sorted(p.parent.name for p in root.rglob(f"{c.name}/*/seed-0.npz"))
        assert stored_keys == sorted([c.key(), old_keys[c.name]])
        assert np.array_equal(old[c.name][0].theta, new[c.name][0].theta)


def test_set_aside_leaves_a_file_another_runner_already_replaced(tmp_path):
    path = tmp_path / "seed-0.npz"
    path.write_text("damaged")
    inode = path.stat().st_ino
    _record().save(tmp_path / "new.npz")
    os.replace(tmp_path / "new.npz", path)  # another runner set it aside and stored the run meanwhile
    assert store.set_aside(path, inode) is None and LearningRecord.load(path).iterations == 10
    assert store.set_aside(tmp_path / "gone.npz") is None
    path.write_text("damaged again")
    first = store.set_aside(path)
    path.write_text("and again, within the same second")
    second = store.set_aside(path)
    assert first != second and first.read_text() == "damaged again" and not path.exists()
    assert second.name.startswith(f"seed-0.npz{store.DAMAGED_SUFFIX}")


def test_warm_start_sets_a_damaged_starting_run_aside(root, monkeypatch):
    """A warm-started experiment whose starting run is damaged sets it aside and starts from its recomputation."""
    base = ex.get_experiment("cartpole-baseline")
    b0 = base.configs[0]
    cheap = ex.scaled(replace(base, configs=(replace(b0, method=replace(b0.method, target=None)),)), seeds=1,
                      budget=8000)
    monkeypatch.setitem(ex.EXPERIMENTS, "cartpole-baseline", cheap)
    t54 = ex.get_experiment("table-5.4")
    warm = ex.scaled(replace(t54, configs=t54.configs[:1]), seeds=1, budget=4000)
    first = es.run_experiment(warm, root=root)[warm.configs[0].name][0]
    path = runner.run_path(es.experiment_folder(cheap, root), cheap.configs[0], 0)
    _damage(path, "truncated")
    stored = list(es.experiment_folder(warm, root).rglob("seed-0.npz"))
    assert len(stored) == 1
    stored[0].unlink()  # so the warm-started run is computed again, from the recomputed start
    with pytest.warns(store.DamagedRunWarning, match="set aside"):
        again = es.run_experiment(warm, root=root)[warm.configs[0].name][0]
    assert list(path.parent.glob(f"seed-0.npz{store.DAMAGED_SUFFIX}*"))
    np.testing.assert_array_equal(again.theta, first.theta)


# -------------------------------------------------------------------------- the command line
CAMPAIGN = ["table-5.1", "--seeds", "1", "--budget", "20000"]


def test_the_command_line_on_a_damaged_folder(tmp_path):
    """The two commands on a folder with a truncated and an overwritten run file, as a user types them."""
    env = {**os.environ, "SAFEPG_RESULTS": str(tmp_path)}

    def safepg(*argv):
        return subprocess.run([sys.executable, "-m", "safepg", *argv], env=env, capture_output=True, text=True,
                              timeout=300)

    assert safepg("run", *CAMPAIGN, "--jobs", "1", "--quiet").returncode == 0
    before = json.loads(safepg("report", *CAMPAIGN, "--json").stdout)
    truncated, garbage = sorted((tmp_path / "table-5.1").rglob("seed-0.npz"))[:2]
    truncated.write_bytes(truncated.read_bytes()[:1000])
    garbage.write_text("overwritten\n")

    rep = safepg("report", *CAMPAIGN)
    assert rep.returncode == 1 and rep.stdout == "" and "Traceback" not in rep.stderr
    lines = rep.stderr.splitlines()
    assert lines[0] == (f"safepg: damaged run file {truncated}: not a whole .npz archive (truncated or "
                        "overwritten) (BadZipFile: File is not a zip file)")
    assert lines[1] == (f"safepg: damaged run file {garbage}: not an .npz archive (overwritten with other "
                        "data) (ValueError)")
    assert lines[2].startswith("safepg: 2 damaged run files of table-5.1; repair with: "
                               "python -m safepg run table-5.1 --seeds 1 --budget 20000 ")
    assert len(lines) == 3 and truncated.exists() and garbage.exists()  # report changes nothing

    run = safepg("run", *CAMPAIGN, "--jobs", "1", "--quiet")
    assert run.returncode == 0 and "Traceback" not in run.stderr
    warned = run.stderr.splitlines()
    assert len(warned) == 2
    for line, path in zip(warned, (truncated, garbage)):
        (aside,) = path.parent.glob(f"seed-0.npz{store.DAMAGED_SUFFIX}*")
        assert line.startswith(f"safepg: warning: damaged run file {path} set aside as {aside.name}, "
                               "its run is computed again: ")
    fixed = safepg("report", *CAMPAIGN, "--json")
    assert fixed.returncode == 0 and fixed.stderr == ""
    assert json.loads(fixed.stdout) == before


def test_cli_report_lists_every_damaged_file(root, capsys):
    exp = small()
    es.run_experiment(exp, jobs=1, progress=False)
    for path, how in zip(_files(exp), ("empty", "wrong shape", "missing array")):
        _damage(path, how)
    capsys.readouterr()
    assert main(["report", "table-5.2", "--seeds", "2", "--budget", "3000"]) == 1
    out, err = capsys.readouterr()
    assert out == "" and err.count("safepg: damaged run file ") == 3
    assert ": empty (EOFError" in err and "arrays that do not form one run (batch_size must have shape" in err
    assert "not a saved run (an array or the metadata is missing or extra)" in err
    assert "repair with: python -m safepg run table-5.2 --seeds 2 --budget 3000" in err
