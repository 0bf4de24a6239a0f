"""Wall time of Chapter 5's experiments at the thesis's scale, from an empty cache.

Runs each named experiment (default: every one in ``safepg.thesis.experiments``) into a fresh
results folder with all cores, then reruns it to time the cached path, and merges the
timings into ``benchmarks/campaign_timings.json`` (which the chapters quote).

Usage: ``python benchmarks/bench_campaign.py [--experiments table-5.1 table-5.2] [--keep DIR]``
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import tempfile
import time
from pathlib import Path

from safepg.thesis.experiment_store import run_experiment
from safepg.thesis.experiments import EXPERIMENTS
from safepg.thesis.report import report

TIMINGS = Path(__file__).with_name("campaign_timings.json")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--experiments", nargs="+", default=list(EXPERIMENTS))
    ap.add_argument("--keep", type=Path, help="store the results here instead of a temp folder")
    ap.add_argument("--jobs", type=int, default=-1)
    args = ap.parse_args()
    root = args.keep or Path(tempfile.mkdtemp(prefix="safepg-bench-"))
    timings = {}
    try:
        for name in args.experiments:
            t = time.perf_counter()
            run_experiment(name, jobs=args.jobs, root=root)
            cold = time.perf_counter() - t
            t = time.perf_counter()
            recs = run_experiment(name, jobs=args.jobs, root=root, progress=False)
            warm = time.perf_counter() - t
            timings[name] = {"cold_s": round(cold, 1), "warm_s": round(warm, 2),
                             "runs": sum(len(v) for v in recs.values())}
            print(f"{name}: cold {cold:.1f} s, cached {warm:.2f} s", flush=True)
            rep = report(name, recs)
            for row in rep["configs"]:
                print(f"  {row['name']:36s} upsilon_bar={row['upsilon_bar']['mean']:.4f} "
                      f"improvement_ratio={row['improvement_ratio']['mean']:.4f}  thesis={row['thesis']}")
        total = sum(t["cold_s"] for t in timings.values())
        print(json.dumps({"cores": os.cpu_count(), "total_cold_s": round(total, 1), **timings}))
        stored = json.loads(TIMINGS.read_text()) if TIMINGS.exists() else {}
        stored.update({k: {**v, "cores": os.cpu_count(), "date": time.strftime("%Y-%m-%d")}
                       for k, v in timings.items()})
        TIMINGS.write_text(json.dumps(stored, indent=1, sort_keys=True) + "\n")
    finally:
        if args.keep is None:
            shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    main()
