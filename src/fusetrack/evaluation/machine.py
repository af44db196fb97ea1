"""The machine a run was timed on, written beside every wall time (``summary.json``, benchmark
results): wall times compare only between like machines. Two machines that both call themselves
"AMD EPYC" ran the same full-size Ercan et al. reproduction 1.4x apart (1.1-1.6x per
configuration; issue 19, item 6), so the model string alone is not enough: ``cpu_arch`` is the microarchitecture LLVM (which compiles
the Numba kernels) detects, e.g. ``znver3`` or ``znver4``, and ``avx512`` whether the kernels
may use 512-bit vectors."""

from __future__ import annotations

import os
import platform
from pathlib import Path
from typing import Any


def _cpuinfo() -> list[str]:
    try:
        return Path("/proc/cpuinfo").read_text().splitlines()
    except OSError:
        return []


def cpu_model() -> str:
    """The CPU's model name from ``/proc/cpuinfo`` (``platform.processor()`` elsewhere)."""
    for line in _cpuinfo():
        if line.lower().startswith("model name"):
            return line.split(":", 1)[1].strip()
    return platform.processor() or "unknown"


def cpu_arch() -> str:
    """The microarchitecture LLVM compiles the Numba kernels for (``"unknown"`` without llvmlite)."""
    try:
        import llvmlite.binding as llvm
    except ImportError:  # pragma: no cover - numba depends on llvmlite
        return "unknown"
    return str(llvm.get_host_cpu_name())


def has_avx512() -> bool:
    """The CPU reports AVX-512 (``avx512f``) in ``/proc/cpuinfo``."""
    return any(line.startswith("flags") and " avx512f" in line for line in _cpuinfo())


def machine() -> dict[str, Any]:
    """``{"cpu_model", "cpu_arch", "avx512", "cores", "platform"}`` of this machine."""
    return {
        "cpu_model": cpu_model(),
        "cpu_arch": cpu_arch(),
        "avx512": has_avx512(),
        "cores": os.cpu_count(),
        "platform": platform.platform(),
    }


def machine_line(facts: dict[str, Any]) -> str:
    """``"2 cores, AMD EPYC (znver4, AVX-512)"``: the machine in a report's header."""
    arch = facts.get("cpu_arch", "unknown")
    isa = ", AVX-512" if facts.get("avx512") else ""
    return f"{facts.get('cores', '?')} cores, {facts.get('cpu_model', 'unknown')} ({arch}{isa})"
