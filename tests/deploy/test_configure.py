#!/usr/bin/env python3
"""Configure never fails on an optional part: with PEAKCAST_WITH_MPI=AUTO, an MPI install that is
broken (a wrapper naming folders that are not there, as openmpi-bin leaves it without
libopenmpi-dev; a wrapper that fails) or missing leaves distributed rendering out with one status
line; ON insists and names what is wrong. Each case configures a scratch build (no compiling)."""
import os, pathlib, subprocess, sys, tempfile

ROOT = pathlib.Path(__file__).resolve().parents[2]

# What `mpicc` answers on a Debian machine with openmpi-bin but not libopenmpi-dev: folders that
# are not there (FindMPI then makes an imported target with a non-existent include path, which
# fails CMake's own try_compile).
HEADERS_MISSING = """#!/bin/sh
case "$*" in
  *showme:compile*) echo "-I/nonexistent/openmpi/include -pthread" ;;
  *showme:link*) echo "-pthread -L/nonexistent/openmpi/lib -lmpi" ;;
  *showme:incdirs*) echo "/nonexistent/openmpi/include" ;;
  *showme:libdirs*) echo "/nonexistent/openmpi/lib" ;;
  *showme:libs*) echo "mpi" ;;
  *showme:version*) echo "mpicc: Open MPI 4.1.4 (Language: C)" ;;
  *showme*) echo "gcc -I/nonexistent/openmpi/include -pthread -L/nonexistent/openmpi/lib -lmpi" ;;
  *) echo "mpicc: headers missing" >&2; exit 1 ;;
esac
"""
ALWAYS_FAILS = """#!/bin/sh
echo "mpicc: cannot run" >&2
exit 1
"""


def configure(*args, wrapper=None):
    with tempfile.TemporaryDirectory() as tmp:
        cmd = ["cmake", "-S", str(ROOT), "-B", f"{tmp}/build", "-DPEAKCAST_BUILD_TESTS=OFF", *args]
        if wrapper is not None:
            fake = pathlib.Path(tmp) / "mpicc"
            fake.write_text(wrapper)
            fake.chmod(0o755)
            cmd.append(f"-DMPI_C_COMPILER={fake}")
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=240)
        return r.returncode, r.stdout + r.stderr


def status_line(out):
    lines = [l for l in out.splitlines() if "distributed rendering" in l]
    assert len(lines) == 1, f"want one status line about distributed rendering, got {lines}\n{out[-3000:]}"
    return lines[0]


def test_wrapper_naming_missing_headers_leaves_mpi_out():
    rc, out = configure(wrapper=HEADERS_MISSING)
    assert rc == 0, out[-3000:]
    line = status_line(out)
    assert "distributed rendering off" in line and "/nonexistent/openmpi/include" in line, line


def test_wrapper_that_fails_leaves_mpi_out():
    rc, out = configure(wrapper=ALWAYS_FAILS)
    assert rc == 0, out[-3000:]
    assert "distributed rendering off" in status_line(out)


def test_icet_without_mpi_leaves_mpi_out():
    rc, out = configure("-DCMAKE_DISABLE_FIND_PACKAGE_MPI=ON")
    assert rc == 0, out[-3000:]
    line = status_line(out)
    assert "distributed rendering off" in line and "MPI not found" in line, line


def test_off_does_not_look():
    rc, out = configure("-DPEAKCAST_WITH_MPI=OFF", wrapper=ALWAYS_FAILS)
    assert rc == 0, out[-3000:]
    assert "PEAKCAST_WITH_MPI=OFF" in status_line(out)


def test_on_insists_and_says_why():
    rc, out = configure("-DPEAKCAST_WITH_MPI=ON", wrapper=HEADERS_MISSING)
    assert rc != 0, out[-3000:]
    assert "PEAKCAST_WITH_MPI=ON" in out and "/nonexistent/openmpi/include" in out, out[-3000:]


def test_a_bad_choice_is_refused():
    rc, out = configure("-DPEAKCAST_WITH_MPI=maybe")
    assert rc != 0 and "must be AUTO, ON or OFF" in out, out[-3000:]


if __name__ == "__main__":
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
    import script_tests

    script_tests.run(globals())
