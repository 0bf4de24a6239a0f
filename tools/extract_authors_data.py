"""Extract the authors' raw outputs the book draws beside ours into ``safepg/thesis/data/authors/``.

Reads the authors' public repository ``T3p/adaptive-batch-size`` from a local git mirror (no
network), keeps only the columns the plots and the recomputed tables need, with the original
text of every kept number (nothing is rounded or reformatted), and writes xz-compressed CSV
files and ``MANIFEST.json`` (repository, path, commit, blob, size, header of every source, and
the SHA-256 of every written file). Rerunning it rewrites byte-identical files.

Usage::

    python tools/extract_authors_data.py /path/to/T3p+adaptive-batch-size/repo/.git

Every source is read at commit 5810ee6 ("ready-to-plot data", 2017-10-16), the last tree that
still holds the 2-D LQG, cart-pole and plot folders; ``commit`` in the manifest is the last
commit that changed the file up to there (the version the book cites).
"""

from __future__ import annotations

import hashlib
import io
import json
import lzma
import subprocess
import sys
from pathlib import Path

import numpy as np

REPOSITORY = "https://github.com/T3p/adaptive-batch-size"
READ_AT = "5810ee6332bf14b33d2b66d0d396dae8cd36c996"
OUT = Path(__file__).resolve().parents[1] / "safepg" / "thesis" / "data" / "authors"


class Mirror:
    """The authors' repository as a local git directory."""

    def __init__(self, git_dir: str) -> None:
        self.git_dir = git_dir

    def git(self, *args: str) -> bytes:
        return subprocess.run(["git", "-C", self.git_dir, *args], capture_output=True, check=True).stdout

    def read(self, path: str) -> bytes:
        return self.git("show", f"{READ_AT}:{path}")

    def source(self, path: str, columns: str, key: dict) -> dict:
        """The provenance record of one source file."""
        blob = self.git("rev-parse", f"{READ_AT}:{path}").decode().strip()
        commit = self.git("log", "-1", "--format=%H", READ_AT, "--", path).decode().strip()
        data = self.read(path)
        header = (data.decode().splitlines()[0] if not path.endswith((".npy", ".fig"))
                  else "(NumPy .npy, 4 float64)" if path.endswith(".npy") else "(MATLAB figure, a MAT-file)")
        return {"path": path, "commit": commit, "blob": blob, "bytes": len(data), "header": header,
                "columns": columns, "key": key}


def rows(text: str) -> list[list[str]]:
    """The data rows of an output file: the header line and the blank line skipped, the brackets
    around a printed NumPy vector removed, split on whitespace."""
    out = []
    for line in text.splitlines()[2:]:
        if line.strip():
            out.append(line.replace("[", " ").replace("]", " ").split())
    return out


def write(name: str, columns: list[str], table: list[list[str]], description: str, sources: list[dict],
          manifest: dict) -> None:
    """Write one CSV (xz-compressed when its name ends in .xz) and its manifest entry."""
    text = ",".join(columns) + "\n" + "".join(",".join(r) + "\n" for r in table)
    raw = text.encode()
    # xz's container records no time stamp or file name: the same text gives the same bytes.
    data = lzma.compress(raw, preset=9 | lzma.PRESET_EXTREME) if name.endswith(".xz") else raw
    (OUT / name).write_bytes(data)
    manifest["files"][name] = {"description": description, "columns": columns, "rows": len(table),
                               "bytes": len(data), "sha256": hashlib.sha256(data).hexdigest(),
                               "sources": sources}


def table51(m: Mirror, manifest: dict) -> None:
    sources, table = [], []
    for sigma in (0.5, 1.0):
        for n in (10_000, 1_000, 100):
            for alpha, tag in ((1e-3, "0_001"), (1e-4, "0_0001"), (1e-5, "1e-05"), (1e-6, "1e-06")):
                # The sigma tags of the file names differ between the N = 100 files and the others.
                stag = {0.5: "sigma0_5" if n != 100 else "sigma_0_5", 1.0: "sigma_1"}[sigma]
                path = f"lqg/results/final/rate_N{n}_alpha{tag}_{stag}_est1_sample1.out"
                i = len(sources)
                sources.append(m.source(path, "iteration theta J(closed form, Sigma = sigma) J_hat",
                                        {"sigma": sigma, "N": n, "alpha": alpha}))
                body = rows(m.read(path).decode())
                assert len(body) == 1_000_000 // n, path
                table += [[str(i), r[1], r[2]] for r in body]
    write("table51.csv.xz", ["source", "theta", "J"], table,
          "Table 5.1: one run per cell, G(PO)MDP with fixed N and alpha from theta_0 = -0.575853, 10^6 "
          "trajectories; theta before each update and the closed-form J at it (their J reads sigma as the "
          "variance).", sources, manifest)


#: Table 5.2's rows: (estimator index, bound index, delta tag) -> (estimator, bound, empirical range, delta).
T52 = [(0, 0, "0_95", "reinforce", "chebyshev", False, 0.95), (0, 0, "0_75", "reinforce", "chebyshev", False, 0.75),
       (0, 0, "0_5", "reinforce", "chebyshev", False, 0.5), (1, 1, "0_95", "gpomdp", "chebyshev", False, 0.95),
       (1, 1, "0_75", "gpomdp", "chebyshev", False, 0.75), (1, 1, "0_5", "gpomdp", "chebyshev", False, 0.5),
       (1, 1, "0_25", "gpomdp", "chebyshev", False, 0.25), (1, 1, "0_05", "gpomdp", "chebyshev", False, 0.05),
       (1, 2, "0_95", "gpomdp", "hoeffding", False, 0.95), (1, 3, "0_95", "gpomdp", "bernstein", False, 0.95),
       (1, 4, "0_95", "gpomdp", "hoeffding", True, 0.95), (1, 5, "0_95", "gpomdp", "bernstein", True, 0.95)]


def table52(m: Mirror, manifest: dict) -> None:
    listed = set(m.git("ls-tree", "--name-only", READ_AT, "lqg/results/final/").decode().split())
    sources, table = [], []
    for est_i, bound_i, dtag, est, bound, er, delta in T52:
        for run in range(1, 6):
            path = f"lqg/results/final/adabatch_est{est_i}_bound{bound_i}__delta{dtag}_sample{run}.out"
            if path not in listed:  # only run 1 of Bernstein e.r. is committed
                continue
            i = len(sources)
            sources.append(m.source(path, "iteration N theta alpha J(closed form) J_hat",
                                    {"estimator": est, "bound": bound, "empirical_range": er, "delta": delta,
                                     "run": run}))
            table += [[str(i), r[1], r[2], r[4], r[5]] for r in rows(m.read(path).decode())]
    write("table52.csv.xz", ["source", "N", "theta", "J", "J_hat"], table,
          "Table 5.2 (and Figures 5.1-5.4): Algorithm 4.1 on the 1-D LQG from theta = 0, 3*10^7 trajectories; "
          "batch size, theta before the update, the closed-form J at it and the measured (discounted) return of "
          "every iteration, 5 runs per row (1 for Bernstein e.r.).",
          sources, manifest)


def figures51_52(m: Mirror, manifest: dict) -> None:
    names = [("chebyshev_reinforce_095", "reinforce", "chebyshev", False, 0.95),
             ("chebyshev_reinforce_075", "reinforce", "chebyshev", False, 0.75),
             ("chebyshev_reinforce_050", "reinforce", "chebyshev", False, 0.5),
             ("chebyshev_gpomdp_095", "gpomdp", "chebyshev", False, 0.95),
             ("chebyshev_gpomdp_075", "gpomdp", "chebyshev", False, 0.75),
             ("chebyshev_gpomdp_050", "gpomdp", "chebyshev", False, 0.5),
             ("chebyshev_gpomdp_025", "gpomdp", "chebyshev", False, 0.25),
             ("chebyshev_gpomdp_005", "gpomdp", "chebyshev", False, 0.05),
             ("hoeffding_gpomdp_095", "gpomdp", "hoeffding", False, 0.95),
             ("bernstein_gpomdp_095", "gpomdp", "bernstein", False, 0.95),
             ("hoeff_emp_gpomdp_095", "gpomdp", "hoeffding", True, 0.95),
             ("bern_emp_gpomdp_095", "gpomdp", "bernstein", True, 0.95)]
    sources, table = [], []
    for stem, est, bound, er, delta in names:
        path = f"processed_data/{stem}.txt"
        i = len(sources)
        sources.append(m.source(path, "trajectory performance (the closed-form J of their run 1 on a 1000-trajectory "
                                      "grid, plots/scaleData.m)", {"estimator": est, "bound": bound,
                                                                    "empirical_range": er, "delta": delta}))
        body = m.read(path).decode().splitlines()[1:]  # one header line, no blank line
        table += [[str(i), *line.split()] for line in body if line.strip()]
    write("figures51_52.csv.xz", ["source", "trajectories", "J"], table,
          "Figures 5.1-5.2: the authors' plotted curves. Each is one run, their run 1 (sample1) of the row, mapped "
          "by plots/scaleData.m onto a grid of 1000 trajectories: at x = 1000 (i + 1) the closed-form J of the "
          "policy that collected the last batch ended before 1000 i trajectories (not a 5-run mean).",
          sources, manifest)


def figure_lines(data: bytes) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """The plotted lines of a MATLAB ``.fig`` file (a MAT-file holding the figure's object tree):
    each line's ``DisplayName`` and its ``XData``, ``YData``."""
    import scipy.io

    tree = scipy.io.loadmat(io.BytesIO(data), squeeze_me=True, struct_as_record=False)["hgS_070000"]
    lines, todo = {}, [tree]
    while todo:
        node = todo.pop()
        props = getattr(node, "properties", None)
        if props is not None and hasattr(props, "YData") and hasattr(props, "DisplayName"):  # a line series
            lines[str(props.DisplayName)] = (np.atleast_1d(props.XData).astype(float),
                                             np.atleast_1d(props.YData).astype(float))
        children = getattr(node, "children", None)
        if children is not None:
            todo.extend(np.atleast_1d(children).ravel())
    return lines


def figure55(m: Mirror, manifest: dict) -> None:
    path = "plots/compare_stepsize.fig"
    lines = figure_lines(m.read(path))
    sources, table = [], []
    for i, (key, name) in enumerate((("coordinate", "Non-scalar step size"), ("scalar", "Scalar step size"))):
        x, y = lines[name]
        sources.append(m.source(path, f"the line '{name}': XData YData", {"run": key}))
        table += [[str(i), str(int(a)), repr(float(b))] for a, b in zip(x, y)]
    write("figure55.csv.xz", ["source", "trajectories", "J"], table,
          "Figure 5.5 as the authors plotted it: the two lines of their MATLAB figure (16 x the expectation), each "
          "float64 written as its shortest exact decimal.", sources, manifest)


#: The 2-D runs: (key, path, the theta-free copy it must agree with).
LQG2D = [("adaptive", "lqgnd/results/adabatch_est1_bound5__delta0_95_sample1.out",
          "lqgnd/results/notheta/adabatch_theta0_sample1.out"),
         ("N=1000", "lqgnd/results/polgrad_est1_bound5__delta0_95_sample1.out",
          "lqgnd/results/notheta/polgrad_theta0_N1000_alpha6_sample1.out"),
         ("coordinate", "lqgnd/results/vector_ex.out", "lqgnd/results/notheta/vector_ex.out"),
         ("scalar", "lqgnd/results/scalar_ex.out", "lqgnd/results/notheta/scalar_ex.out")]


def lqg2d(m: Mirror, manifest: dict) -> None:
    sources, table, ends = [], [], []
    for i, (key, path, copy) in enumerate(LQG2D):
        sources.append(m.source(path, "iteration N theta11 theta12 theta21 theta22 alpha J(16 x closed form) J_hat",
                                {"run": key}))
        body = rows(m.read(path).decode())
        # The theta-free copy the authors' plot scripts read holds the same numbers.
        assert [[r[1], r[6], r[7], r[8]] for r in body] == [[r[1], *r[2:]] for r in rows(m.read(copy).decode())], path
        table += [[str(i), r[1], r[6], r[7], r[8]] for r in body]
        ends += [[str(i), r[0], *r[2:6], r[7]] for r in (body[0], body[-1])]
    write("lqg2d.csv.xz", ["source", "N", "alpha", "J", "J_hat"], table,
          "Section 5.2 (Table 5.3, Figures 5.5-5.8): the 2-D LQG runs from theta = 0, 3*10^7 trajectories; batch "
          "size, step size, the closed-form J as their code computes it (16 x the expectation over the initial "
          "state) and the measured discounted return. Table 5.3's N = 100 run is not in the repository.",
          sources, manifest)
    write("lqg2d_theta.csv", ["source", "iteration", "theta11", "theta12", "theta21", "theta22", "J"], ends,
          "The first and last logged parameters of each 2-D run with their J (16 x scale); the last row is the "
          "parameter before the final update.", sources, manifest)


CARTPOLE = [("adaptive", "cartpole/results/tweak2_adabatch.out", "cartpole/results/notheta/tweak2_adabatch.out"),
            ("fixed", "cartpole/results/long_tweak2_fixed.out", "cartpole/results/notheta/long_tweak2_fixed.out"),
            ("fixed-short", "cartpole/results/tweak2_fixed.out", "cartpole/results/notheta/tweak2_fixed.out")]


def cartpole(m: Mirror, manifest: dict) -> None:
    sources, table = [], []
    for i, (key, path, copy) in enumerate(CARTPOLE):
        sources.append(m.source(path, "iteration N theta_x theta_xdot theta_beta theta_betadot alpha J_hat",
                                {"run": key}))
        body = rows(m.read(path).decode())
        # The theta-free copy the authors' plot script reads holds the same numbers.
        assert [[r[1], r[6], r[7]] for r in body] == [r[1:] for r in rows(m.read(copy).decode())], path
        table += [[str(i), r[1], *r[2:6], r[6], r[7]] for r in body]
    path = "cartpole/polgrad_N4000_alpha2.out"
    sources.append(m.source(path, "iteration N alpha theta_x theta_xdot theta_beta theta_betadot J_hat",
                            {"run": "baseline"}))
    table += [[str(len(sources) - 1), r[1], *r[3:7], r[2], r[7]] for r in rows(m.read(path).decode())]
    write("cartpole.csv.xz", ["source", "N", "theta_x", "theta_xdot", "theta_beta", "theta_betadot", "alpha",
                              "J_hat"], table,
          "Section 5.3 (Table 5.4, Figure 5.9): the doubled-pole runs from their baseline policy (adaptive; the "
          "coordinate-step 'vanilla' N = 4000, alpha = 0.01, and its shorter first run) and the baseline search "
          "(N = 4000, alpha = 0.01 from theta = 0); theta before each update, the batch's mean undiscounted return.",
          sources, manifest)
    path = "cartpole/theta_star.npy"
    theta = np.load(io.BytesIO(m.read(path)))
    assert theta.shape == (4,) and theta.dtype == np.float64
    write("cartpole_theta_star.csv", ["theta_x", "theta_xdot", "theta_beta", "theta_betadot"],
          [[repr(float(v)) for v in theta]],
          "The baseline policy every doubled-pole run starts from (their theta_star.npy, the parameter after "
          "the 72nd update of the baseline search), each float64 written as its shortest exact decimal.",
          [m.source(path, "4 float64", {"run": "baseline"})], manifest)


def main(git_dir: str) -> None:
    m = Mirror(git_dir)
    OUT.mkdir(parents=True, exist_ok=True)
    manifest = {"repository": REPOSITORY, "read_at": READ_AT,
                "extracted_by": "tools/extract_authors_data.py",
                "note": "Columns keep the original text of every number; 'commit' is the last commit that changed "
                        "the source up to read_at, 'blob' its git object id, 'bytes' its size.",
                "files": {}}
    for part in (table51, table52, figures51_52, lqg2d, figure55, cartpole):
        part(m, manifest)
    (OUT / "MANIFEST.json").write_text(json.dumps(manifest, indent=1) + "\n")
    total = sum(f["bytes"] for f in manifest["files"].values())
    print(f"{len(manifest['files'])} files, {total} bytes")


if __name__ == "__main__":
    main(sys.argv[1])
