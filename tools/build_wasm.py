"""Compile the page learner's WebAssembly kernel: ``make wasm``.

``safepg/thesis/explorers/wasm/lqg2d_kernel.c`` -> ``safepg/thesis/explorers/static/lqg2d_kernel.wasm``
with the clang of the pinned ``ziglang`` package (requirements-dev.txt), so that every machine
compiles the same bytes: tests/test_wasm_kernel.py compiles it again and compares.

Usage: python tools/build_wasm.py [--out PATH]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SOURCE = ROOT / "safepg" / "thesis" / "explorers" / "wasm" / "lqg2d_kernel.c"
BINARY = ROOT / "safepg" / "thesis" / "explorers" / "static" / "lqg2d_kernel.wasm"
#: -msimd128: two trajectories per f64x2; -ffp-contract=off: no fused multiply-add, ever (the
#: JavaScript's bits); a 64 kB stack (the kernel keeps a few doubles on it); no name section.
FLAGS = ("--target=wasm32-freestanding", "-O2", "-g0", "-msimd128", "-ffp-contract=off", "-nostdlib",
         "-Wl,--no-entry", "-Wl,--export=__heap_base", "-Wl,-z,stack-size=65536", "-Wl,--strip-all")


def compile_kernel(out: Path) -> None:
    """Compile :data:`SOURCE` to ``out`` (raises ``CalledProcessError`` with clang's message)."""
    subprocess.run([sys.executable, "-m", "ziglang", "cc", *FLAGS, "-o", str(out.resolve()), SOURCE.name], check=True,
                   cwd=SOURCE.parent)
    out.chmod(0o644)  # the linker marks its output executable; a module is data


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=BINARY)
    compile_kernel(parser.parse_args().out)


if __name__ == "__main__":
    main()
