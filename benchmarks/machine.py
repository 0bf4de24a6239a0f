"""The machine a benchmark ran on, for its record: every time is stored with the CPU it was measured on."""

from __future__ import annotations

import os
import platform
from pathlib import Path


def cpu() -> dict[str, object]:
    """The CPU's model name, core count and vector extensions (from /proc/cpuinfo), and the instruction set
    numba compiles for (``NUMBA_CPU_NAME``, ``host`` when unset)."""
    info = Path("/proc/cpuinfo").read_text() if Path("/proc/cpuinfo").exists() else ""
    name = next((line.split(":", 1)[1].strip() for line in info.splitlines() if line.startswith("model name")),
                platform.processor())
    flags = set(next((line.split(":", 1)[1].split() for line in info.splitlines() if line.startswith("flags")), []))
    return {"model": name, "cores": os.cpu_count(), "avx2": "avx2" in flags, "avx512f": "avx512f" in flags,
            "numba_cpu_name": os.environ.get("NUMBA_CPU_NAME", "host")}
