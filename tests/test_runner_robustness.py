"""The experiment runner under real conditions: a Dask cluster, a SIGKILL, two runners at once,
and the command line's input checks."""

import json
import os
import signal
import subprocess
import sys
import time
from dataclasses import fields, replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from safepg import runner, store
from safepg.cli import main
from safepg.learning import LearningRecord
from safepg.options import FixedStep, Vanilla
from safepg.thesis import experiment_store as es
from safepg.thesis import experiments as ex

#: The campaign the kill and concurrency tests run from the command line: 2 configs x 4 seeds,
#: 10 iterations each, about 0.25 s per run.
CAMPAIGN = ["figures-5.5-5.6", "--seeds", "4", "--budget", "20000"]
RUNS = 8


def _env(results: Path) -> dict[str, str]:
    return {**os.environ, "SAFEPG_RESULTS": str(results), "PYTHONUNBUFFERED": "1"}


def _start(results: Path, *prefix: str) -> subprocess.Popen:
    """``python -m safepg run CAMPAIGN --jobs 1`` (or ``prefix`` in place of ``-m safepg``)."""
    cmd = [sys.executable, *(prefix or ("-m", "safepg")), "run", *CAMPAIGN, "--jobs", "1", "--quiet"]
    return subprocess.Popen(cmd, env=_env(results), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


def _runs(results: Path) -> list[Path]:
    return sorted(p for p in results.rglob("seed-*.npz") if not p.name.endswith(store.TEMP_SUFFIX))


def _temps(results: Path) -> list[Path]:
    return sorted(results.rglob(f"*{store.TEMP_SUFFIX}"))


def _report(results: Path, capsys, monkeypatch) -> dict:
    """What ``python -m safepg report CAMPAIGN --json`` prints for ``results``."""
    monkeypatch.setenv("SAFEPG_RESULTS", str(results))
    capsys.readouterr()
    assert main(["report", *CAMPAIGN, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def _wait_for(condition, proc: subprocess.Popen, timeout: float = 120.0) -> None:
    end = time.monotonic() + timeout
    while not condition():
        assert proc.poll() is None, f"the runner ended before it could be killed: {proc.stderr.read()}"
        assert time.monotonic() < end, "timed out waiting for the runner"
        time.sleep(0.02)


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory) -> Path:
    """The campaign run once without interruption (in this process), in its own folder."""
    results = tmp_path_factory.mktemp("uninterrupted")
    exp = ex.scaled(ex.get_experiment(CAMPAIGN[0]), seeds=int(CAMPAIGN[2]), budget=int(CAMPAIGN[4]))
    es.run_experiment(exp, jobs=1, root=results, progress=False)
    return results


def assert_same_records(a: dict[str, list[LearningRecord]], b: dict[str, list[LearningRecord]]) -> None:
    """Bit for bit: every array (values and dtype), the config and the flags."""
    assert a.keys() == b.keys()
    for name in a:
        assert len(a[name]) == len(b[name]) > 0
        for ra, rb in zip(a[name], b[name]):
            for f in fields(LearningRecord):
                x, y = getattr(ra, f.name), getattr(rb, f.name)
                if isinstance(x, np.ndarray):
                    assert x.dtype == y.dtype and x.shape == y.shape, (name, f.name)
                    assert x.tobytes() == y.tobytes(), (name, f.name)  # NaN == NaN, -0.0 != 0.0
                else:
                    assert x == y, (name, f.name)


# -------------------------------------------------------------------------- a real Dask cluster
def test_dask_cluster_gives_the_serial_records_and_the_client_stores_them(tmp_path, monkeypatch):
    import joblib
    from distributed import Client, LocalCluster, get_task_stream

    e = ex.get_experiment("table-5.2")
    exp = ex.scaled(replace(e, configs=e.configs[:2]), seeds=2, budget=10_000)
    serial = es.run_experiment(exp, jobs=1, root=tmp_path / "serial", progress=False)

    saved = []  # save_atomic as seen by this (the client) process
    save = store.save_atomic
    monkeypatch.setattr(runner, "save_atomic", lambda rec, path: (saved.append(path), save(rec, path)))
    with (LocalCluster(n_workers=2, processes=True, threads_per_worker=1, dashboard_address=None) as cluster,
          Client(cluster) as client):
        worker_pids = set(client.run(os.getpid).values())
        with get_task_stream(client) as tasks, joblib.parallel_config(backend="dask"):
            remote = es.run_experiment(exp, root=tmp_path / "dask", progress=False)
    assert len(worker_pids) == 2 and os.getpid() not in worker_pids
    assert tasks.data and all("_compute_task" in t["key"] for t in tasks.data)  # the runs ran on the workers
    assert sorted(saved) == _runs(tmp_path / "dask") and len(saved) == 4  # ... and the client wrote them
    assert_same_records(serial, remote)
    assert_same_records(serial, es.load_experiment(exp, root=tmp_path / "dask"))


def test_warm_start_is_resolved_before_dispatch(tmp_path, monkeypatch):
    """A table-5.4 worker gets its starting policy with the task and never reads the store."""
    base = ex.get_experiment("cartpole-baseline")
    b0 = base.configs[0]
    cheap = ex.scaled(replace(base, configs=(replace(b0, method=replace(b0.method, target=None)),)), seeds=1,
                      budget=8000)
    monkeypatch.setitem(ex.EXPERIMENTS, "cartpole-baseline", cheap)
    baseline = es.run_experiment(cheap, jobs=1, root=tmp_path, progress=False)["baseline"][0]

    def no_store(*args, **kwargs):
        raise AssertionError("a run read the store")

    # A run computed in this process may read nothing from the store: its start comes with the task.
    compute = runner._compute

    def compute_without_store(*args):
        with monkeypatch.context() as m:
            m.setattr(store, "load_stored", no_store)
            m.setattr(runner, "load_stored", no_store)
            return compute(*args)

    monkeypatch.setattr(runner, "_compute", compute_without_store)
    t54 = ex.scaled(ex.get_experiment("table-5.4"), seeds=1, budget=8000)
    recs = es.run_experiment(t54, jobs=1, root=tmp_path, progress=False)
    for name in ("adaptive", "N=4000"):
        np.testing.assert_array_equal(recs[name][0].theta[0], baseline.theta_final)
    with pytest.raises(ValueError, match="^theta0 must be given for the warm-started config"):
        t54.configs[0].run(0)


def test_longest_runs_are_dispatched_first(tmp_path, monkeypatch):
    e = ex.get_experiment("table-5.2")
    exp = replace(e, configs=tuple(replace(c, budget=b) for c, b in zip(e.configs[:3], (1000, 3000, 2000))), seeds=1)
    order = []
    compute = runner._compute
    monkeypatch.setattr(runner, "_compute", lambda c, *a: (order.append(c.budget), compute(c, *a))[1])
    es.run_experiment(exp, jobs=1, root=tmp_path, progress=False)
    assert order == [3000, 2000, 1000]


def test_ctrl_c_inside_a_run_stops_the_campaign(tmp_path, monkeypatch):
    """A run that caught Ctrl-C returns a partial record: the runner stops instead of going on."""
    exp = ex.scaled(ex.get_experiment("table-5.1"), seeds=1, budget=10_000)
    compute = runner._compute
    monkeypatch.setattr(runner, "_compute", lambda *a: replace(compute(*a), interrupted=True))
    with pytest.raises(KeyboardInterrupt):
        es.run_experiment(exp, jobs=1, root=tmp_path, progress=False)
    assert _runs(tmp_path) == [] and _temps(tmp_path) == []


# -------------------------------------------------------------------------- SIGKILL and two runners
def test_resume_after_sigkill_gives_the_uninterrupted_report(tmp_path, uninterrupted, capsys, monkeypatch):
    proc = _start(tmp_path)
    _wait_for(lambda: len(_runs(tmp_path)) >= 2, proc)
    proc.send_signal(signal.SIGKILL)
    assert proc.wait(timeout=30) == -signal.SIGKILL
    done = len(_runs(tmp_path))
    assert 2 <= done < RUNS  # killed mid-campaign
    restart = _start(tmp_path)
    assert restart.wait(timeout=300) == 0, restart.stderr.read()
    assert len(_runs(tmp_path)) == RUNS and _temps(tmp_path) == []
    assert _report(tmp_path, capsys, monkeypatch) == _report(uninterrupted, capsys, monkeypatch)


# Runs the CLI with LearningRecord.save hanging after it has written its third temporary file.
_HANG_IN_THIRD_SAVE = """
import runpy, sys, time
from safepg.learning import LearningRecord
save, calls = LearningRecord.save, []
def hanging_save(self, path):
    save(self, path)
    calls.append(path)
    if len(calls) == 3:
        print("SAVING", path, file=sys.stderr, flush=True)
        time.sleep(600)
LearningRecord.save = hanging_save
sys.argv = ["safepg"] + sys.argv[1:]
runpy.run_module("safepg", run_name="__main__", alter_sys=True)
"""


def test_sigkill_mid_save_leaves_a_temp_file_the_restart_removes(tmp_path, uninterrupted, capsys, monkeypatch):
    proc = _start(tmp_path, "-c", _HANG_IN_THIRD_SAVE)
    _wait_for(lambda: len(_runs(tmp_path)) == 2 and len(_temps(tmp_path)) == 1, proc)
    while not (line := proc.stderr.readline()).startswith("SAVING"):  # skip any warnings before it
        assert line, "the runner closed stderr without reaching its third save"
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    (orphan,) = _temps(tmp_path)
    assert f"~{proc.pid}~" in orphan.name
    restart = _start(tmp_path)
    assert restart.wait(timeout=300) == 0, restart.stderr.read()
    assert _temps(tmp_path) == [] and len(_runs(tmp_path)) == RUNS
    assert _report(tmp_path, capsys, monkeypatch) == _report(uninterrupted, capsys, monkeypatch)


def test_two_runners_at_once_on_one_folder(tmp_path, uninterrupted, capsys, monkeypatch):
    first, second = _start(tmp_path), _start(tmp_path)
    for proc in (first, second):
        assert proc.wait(timeout=300) == 0, proc.stderr.read()
    assert _temps(tmp_path) == [] and len(_runs(tmp_path)) == RUNS
    exp = ex.scaled(ex.get_experiment(CAMPAIGN[0]), seeds=int(CAMPAIGN[2]), budget=int(CAMPAIGN[4]))
    assert_same_records(es.load_experiment(exp, root=tmp_path), es.load_experiment(exp, root=uninterrupted))
    assert _report(tmp_path, capsys, monkeypatch) == _report(uninterrupted, capsys, monkeypatch)


def test_only_temp_files_of_dead_writers_are_removed(tmp_path):
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()  # reaped: its pid names no process now
    alive = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    zombie = subprocess.Popen([sys.executable, "-c", "pass"])
    try:
        os.waitid(os.P_PID, zombie.pid, os.WEXITED | os.WNOWAIT)  # exited, left unreaped: a zombie
        host, folder = store.socket.gethostname(), tmp_path / "exp" / "cfg"
        folder.mkdir(parents=True)
        names = {
            "dead": f"seed-0~{host}~{dead.pid}~abc{store.TEMP_SUFFIX}",
            "zombie": f"seed-1~{host}~{zombie.pid}~abc{store.TEMP_SUFFIX}",
            "alive": f"seed-2~{host}~{alive.pid}~abc{store.TEMP_SUFFIX}",
            "self": f"seed-3~{host}~{os.getpid()}~abc{store.TEMP_SUFFIX}",
            "other host, fresh": f"seed-4~elsewhere~{dead.pid}~abc{store.TEMP_SUFFIX}",
            "other host, old": f"seed-5~elsewhere~{alive.pid}~abc{store.TEMP_SUFFIX}",
            "older version, fresh": f"tmpab12cd{store.TEMP_SUFFIX}",
            "older version, old": f"tmpef34gh{store.TEMP_SUFFIX}",
        }
        for label, name in names.items():
            (folder / name).write_bytes(b"partial")
            if label.endswith(", old"):
                past = time.time() - store.TEMP_MAX_AGE - 60
                os.utime(folder / name, (past, past))
        (folder / "seed-0.npz").write_bytes(b"a finished run is never touched")
        removed = {p.name for p in store.remove_stale_temp_files(tmp_path / "exp")}
    finally:
        alive.kill()
        alive.wait()
        zombie.wait()
    stale = {"dead", "zombie", "other host, old", "older version, old"}
    assert removed == {names[k] for k in stale}
    assert {p.name for p in folder.iterdir()} == {names[k] for k in names if k not in stale} | {"seed-0.npz"}


def test_save_names_the_writer_and_leaves_nothing_on_failure(tmp_path, monkeypatch):
    path = tmp_path / "cfg" / "seed-0.npz"
    seen = []

    def failing_save(self, p):
        seen.append(Path(p).name)
        Path(p).write_bytes(b"half")
        raise OSError("disk full")

    record = SimpleNamespace(save=lambda p: failing_save(None, p))
    with pytest.raises(OSError, match="disk full"):
        store.save_atomic(record, path)  # type: ignore[arg-type]
    assert seen[0].startswith(f"seed-0~{store.socket.gethostname()}~{os.getpid()}~") and seen[0].endswith(".tmp.npz")
    assert list(tmp_path.rglob("*")) == [path.parent]


# -------------------------------------------------------------------------- command-line input
def _cli(capsys, *argv: str) -> tuple[int, str, str]:
    capsys.readouterr()
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_zero_seeds_is_a_clear_error_without_traceback(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "safepg", "run", "table-5.1", "--seeds", "0"],
                          env=_env(tmp_path), capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and proc.stdout == ""
    assert "argument --seeds: must be a positive integer, got '0'" in proc.stderr
    assert "Traceback" not in proc.stderr and "null" not in proc.stderr
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize(("argv", "message"), [
    (["run", "table-5.1", "--jobs", "0"], "argument --jobs: must be a number of parallel workers"),
    (["run", "table-5.1", "--seeds", "-2"], "argument --seeds: must be a positive integer"),
    (["run", "table-5.1", "--budget", "0"], "argument --budget: must be a positive integer"),
    (["run", "table-5.1", "--budget", "1.5e3+0.5"], "argument --budget: expected an integer"),
    (["run", "table-5.1", "--budget", "1500.5"], "argument --budget: expected a whole number"),
    (["run", "table-5.1", "--budget", "1e-3"], "argument --budget: expected a whole number"),
    (["run", "table-5.1", "--budget", "inf"], "argument --budget: expected a whole number"),
    (["run", "table-5.1", "--seeds", "1e999999999"], "argument --seeds: expected at most 19 digits"),
    (["report", "table-5.1", "--seeds", "2.5"], "argument --seeds: expected a whole number"),
    (["learn", "--budget", "2.5e3.1"], "argument --budget: expected an integer"),
    (["learn", "--n-min", "0"], "argument --n-min: must be a positive integer"),
    (["learn", "--n-max", "1e5.5"], "argument --n-max: expected an integer"),
    (["learn", "--batch-size", "100.5", "--alpha", "1e-4"], "argument --batch-size: expected a whole number"),
    (["learn", "--seed", "-1"], "argument --seed: must be a non-negative integer"),
])
def test_bad_counts_name_the_parameter(tmp_path, monkeypatch, capsys, argv, message):
    monkeypatch.setenv("SAFEPG_RESULTS", str(tmp_path))
    code, out, err = _cli(capsys, *argv)
    assert code == 2 and out == "" and message in err and "Traceback" not in err
    assert not list(tmp_path.iterdir())


def test_python_api_refuses_zero_jobs_and_seeds(tmp_path):
    with pytest.raises(ValueError, match="^jobs must be"):
        es.run_experiment("table-5.1", seeds=1, budget=1000, jobs=0, root=tmp_path, progress=False)
    for kw in ({"seeds": 0}, {"budget": -5}, {"seeds": 1.0}, {"budget": True}):
        with pytest.raises(ValueError, match=f"^{next(iter(kw))} must be a positive integer"):
            ex.scaled(ex.get_experiment("table-5.1"), **kw)
    assert not list(tmp_path.iterdir())


def test_counts_accept_exact_scientific_notation(tmp_path, monkeypatch, capsys):
    from safepg.cli import integer

    assert [integer(s) for s in ("1e6", "1E6", "3_000_000", "1.5e3", " 200 ", "2.0e2")] == [
        1_000_000, 1_000_000, 3_000_000, 1500, 200, 200]
    code, out, _ = _cli(capsys, "learn", "--budget", "2e3", "--batch-size", "1e2", "--alpha", "1e-4",
                        "--n-min", "1e2", "--n-max", "5e5", "--seed", "0e0", "--quiet")
    assert code == 0 and json.loads(out)["trajectories"] == 2000 and json.loads(out)["iterations"] == 20
    # run and report parse --budget 1e6 as 1000000 (here: nothing stored, so report says what to run).
    monkeypatch.setenv("SAFEPG_RESULTS", str(tmp_path))
    code, out, err = _cli(capsys, "report", "table-5.1", "--seeds", "1", "--budget", "1e6")
    assert "python -m safepg run table-5.1 --seeds 1 --budget 1000000" in err


def test_report_with_nothing_stored_says_which_run_to_type(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("SAFEPG_RESULTS", str(tmp_path))
    for extra, command in (([], "python -m safepg run table-5.1\n"),
                           (["--json"], "python -m safepg run table-5.1\n"),
                           (["--seeds", "2", "--budget", "3e4"],
                            "python -m safepg run table-5.1 --seeds 2 --budget 30000\n")):
        code, out, err = _cli(capsys, "report", "table-5.1", *extra)
        assert code == 1 and out == "" and "null" not in err and "Traceback" not in err
        assert err.startswith("safepg: nothing stored for table-5.1") and err.endswith(command)
    # Partly stored: the report is printed, with a note on what is missing.
    exp = ex.scaled(ex.get_experiment("table-5.1"), seeds=1, budget=10_000)
    exp_one = replace(exp, configs=exp.configs[:1])
    es.run_experiment(exp_one, jobs=1, progress=False)
    code, out, err = _cli(capsys, "report", "table-5.1", "--seeds", "1", "--budget", "1e4", "--json")
    assert code == 0 and json.loads(out)["configs"][0]["seeds"] == 1
    assert "1 of 24 runs of table-5.1 stored" in err
    assert "python -m safepg run table-5.1 --seeds 1 --budget 10000" in err


def test_a_reader_that_stops_reading_gets_no_traceback(tmp_path):
    # As in ``python -m safepg list | head -0``: the pipe is closed before anything is written.
    proc = subprocess.Popen([sys.executable, "-m", "safepg", "list"], env=_env(tmp_path), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    proc.stdout.close()
    err = proc.stderr.read()
    assert proc.wait(timeout=120) == 1
    assert "Traceback" not in err and "BrokenPipeError" not in err and "Exception ignored" not in err, err


def test_equal_budgets_put_adaptive_runs_then_the_smallest_fixed_batches_first(tmp_path, monkeypatch):
    """Table 5.3's configs (adaptive, N = 1000, N = 100 at one budget), given in reverse: adaptive
    first, then N = 100, then N = 1000."""
    e = ex.scaled(ex.get_experiment("table-5.3"), seeds=1, budget=2000)
    order = []
    compute = runner._compute
    monkeypatch.setattr(runner, "_compute", lambda c, *a: (order.append(c.name), compute(c, *a))[1])
    es.run_experiment(replace(e, configs=e.configs[::-1]), jobs=1, root=tmp_path, progress=False)
    assert order == ["adaptive", "N=100", "N=1000"]


@pytest.mark.parametrize("as_text", [True, False])
def test_a_folder_may_be_a_str_or_a_path(tmp_path, as_text):
    cfg = runner.RunConfig("tiny", method=Vanilla(10, FixedStep(1e-3)), budget=40)
    folder = str(tmp_path / "group") if as_text else tmp_path / "group"
    recs = runner.run_configs([cfg], 2, folder, jobs=1, progress=False)
    assert len(recs["tiny"]) == 2 and (tmp_path / "group" / "tiny" / cfg.key() / "seed-1.npz").is_file()
    again = runner.load_configs([cfg], 2, folder)["tiny"]
    assert [r.config["seed"] for r in again] == [0, 1] and runner.stored_run(folder, cfg, 0) is not None
