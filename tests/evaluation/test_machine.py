from fusetrack.evaluation import machine as m


def test_machine_line_names_cores_model_and_architecture():
    facts = {"cpu_model": "AMD EPYC", "cpu_arch": "znver4", "avx512": True, "cores": 2}
    assert m.machine_line(facts) == "2 cores, AMD EPYC (znver4, AVX-512)"
    assert m.machine_line({**facts, "avx512": False}) == "2 cores, AMD EPYC (znver4)"
    assert m.machine_line({}) == "? cores, unknown (unknown)"


def test_cpuinfo_is_read_for_model_and_avx512(monkeypatch):
    lines = ["processor\t: 0", "model name\t: Test CPU 9000", "flags\t\t: fpu sse2 avx2 avx512f"]
    monkeypatch.setattr(m, "_cpuinfo", lambda: lines)
    assert m.cpu_model() == "Test CPU 9000"
    assert m.has_avx512()
    monkeypatch.setattr(m, "_cpuinfo", lambda: [*lines[:2], "flags\t\t: fpu sse2 avx2"])
    assert not m.has_avx512()


def test_machine_of_this_process_names_the_llvm_target():
    facts = m.machine()
    assert facts["cpu_arch"] and facts["cpu_arch"] != "unknown"  # numba brings llvmlite
    assert facts["cores"] >= 1
