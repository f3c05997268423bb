"""The FMU is self-contained: loading it resolves every library other than the C library
(libc, libm and glibc's other parts) and the loader from the FMU's own binaries/linux64/."""
import os
import re
import subprocess
import tempfile
import sys
import zipfile

import pytest
from fmpy import extract, read_model_description

from conftest import ROOT, SANITIZED

GLIBC = re.compile(r"^(libc|libm|libpthread|libdl|librt|ld-linux[-\w]*)\.so")


def system_library_folders():
    """The folders in which the loader's cache finds libraries (ldconfig -p): where an importer's
    LD_LIBRARY_PATH would name the system's copies of the libraries an FMU bundles."""
    out = subprocess.run(["/sbin/ldconfig", "-p"], capture_output=True, text=True).stdout
    return sorted({os.path.dirname(line.split("=>")[1].strip()) for line in out.splitlines() if "=>" in line})


@pytest.mark.skipif(SANITIZED, reason="an instrumented FMU needs the sanitizer runtimes of the machine")
@pytest.mark.parametrize("library_path", ["unset", "system folders"])
def test_libraries_resolve_from_the_fmu(test_fmu, tmp_path, library_path):
    # Also with the system's library folders on LD_LIBRARY_PATH, as many tools launch importers:
    # the bundled libraries come first all the same (DT_RPATH), and the system's OpenBLAS, which
    # its liblapack would bring with a thread, stays out.
    fmu = test_fmu("driven_oscillator")
    folder = extract(str(fmu), unzipdir=str(tmp_path / "unzipped"))
    md = read_model_description(str(fmu))
    binaries = os.path.realpath(os.path.join(folder, "binaries", "linux64"))
    binary = os.path.join(binaries, md.coSimulation.modelIdentifier + ".so")
    # A bare process that only dlopens the binary and looks up fmi2Instantiate.
    # It also lists what the dlopen mapped (from /proc/self/maps), which catches libraries
    # without initialisers that the trace's "calling init" lines would miss.
    script = ("import ctypes, sys\n"
              "def mapped():\n"
              "    return {l.split()[-1] for l in open('/proc/self/maps') if '.so' in l}\n"
              "def threads():\n"
              "    return len(__import__('os').listdir('/proc/self/task'))\n"
              "before, started = mapped(), threads()\n"
              "lib = ctypes.CDLL(sys.argv[1], mode=ctypes.RTLD_LOCAL)\n"
              "lib.fmi2Instantiate\n"
              "print('threads', threads() - started)\n"
              "print('loaded', ' '.join(sorted(mapped() - before)))\n")
    env = dict(os.environ, LD_DEBUG="libs")
    env.pop("LD_LIBRARY_PATH", None)
    if library_path == "system folders":
        env["LD_LIBRARY_PATH"] = ":".join(system_library_folders())
        assert env["LD_LIBRARY_PATH"]
    out = subprocess.run([sys.executable, "-c", script, binary], env=env, capture_output=True, text=True)
    assert out.returncode == 0 and "loaded" in out.stdout, out.stderr[-2000:]
    # Loading starts no thread in the importer's process (OpenBLAS would start one per core:
    # the FMU carries the reference BLAS instead, fmu/bundle_runtime.cmake).
    assert "threads 0" in out.stdout, out.stdout
    # Only what is loaded after the dlopen: the Python interpreter's own libraries come first.
    trace = out.stderr[out.stderr.find(binary):]
    loaded = re.findall(r"calling init: (\S+)", trace)
    assert any(path.endswith(md.coSimulation.modelIdentifier + ".so") for path in loaded), trace[-2000:]
    loaded += out.stdout.split("loaded", 1)[1].split()
    outside = [p for p in loaded
               if os.path.dirname(os.path.realpath(p)) != binaries and not GLIBC.match(os.path.basename(p))]
    assert not outside, f"loaded from outside the FMU: {outside}"
    bundled = [p for p in loaded if os.path.dirname(os.path.realpath(p)) == binaries]
    names = " ".join(os.path.basename(p) for p in bundled)
    assert "libjansson" in names and "libklu" in names and "libblas" in names, names
    assert "openblas" not in names, names


@pytest.mark.skipif(SANITIZED, reason="an instrumented FMU needs the sanitizer runtimes of the machine")
def test_the_fmu_starts_no_threads_and_is_unloaded_whole(package, tmp_path):
    """The cholmod solver on 6144 unknowns factorises supernodally, whose loops CHOLMOD would run in
    an OpenMP team of 4 threads that outlived the instance: fmpy unloads the FMU after
    fmi2FreeInstance, and with it went libgomp, under those idle threads, which crashed the
    importer at their next wake-up. The loops now run on the calling thread
    (lib/cholmod_factorize.c): no thread is started, even where OMP_THREAD_LIMIT allows 4, and
    after fmi2FreeInstance nothing of the FMU stays mapped (a process that loads FMUs again and
    again keeps no copies)."""
    fmu = package(ROOT / "models" / "cloth.json", ["n=32"])
    script = ("import os, sys\n"
              "from fmpy import extract, read_model_description\n"
              "from fmpy.fmi2 import FMU2Slave\n"
              "md = read_model_description(sys.argv[1])\n"
              "s = FMU2Slave(guid=md.guid, unzipDirectory=extract(sys.argv[1], sys.argv[2]),\n"
              "              modelIdentifier=md.coSimulation.modelIdentifier, instanceName='x')\n"
              "vr = {v.name: v.valueReference for v in md.modelVariables}\n"
              "threads = lambda: len(os.listdir('/proc/self/task'))\n"
              "before = threads()\n"
              "s.instantiate(); s.setupExperiment(startTime=0.0); s.enterInitializationMode()\n"
              "s.setString([vr['solver.linear_solver']], ['cholmod']); s.exitInitializationMode()\n"
              "for k in range(3): s.doStep(0.002 * k, 0.002)\n"
              "started = threads() - before\n"
              "s.terminate(); s.freeInstance()\n"
              "maps = open('/proc/self/maps').read()\n"
              "print('started', started, 'libgomp', 'libgomp' in maps,\n"
              "      'binary', md.coSimulation.modelIdentifier + '.so' in maps)\n")
    env = dict(os.environ, OMP_THREAD_LIMIT="4")
    env.pop("LD_LIBRARY_PATH", None)
    out = subprocess.run([sys.executable, "-c", script, str(fmu), str(tmp_path / "unzipped")], env=env,
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.split() == ["started", "0", "libgomp", "False", "binary", "False"], out.stdout


@pytest.mark.skipif(SANITIZED, reason="an instrumented FMU exports the sanitizer's symbols too")
def test_only_fmi2_symbols_are_exported(test_fmu, tmp_path):
    fmu = test_fmu("driven_oscillator")
    folder = extract(str(fmu), unzipdir=str(tmp_path / "unzipped"))
    md = read_model_description(str(fmu))
    binary = os.path.join(folder, "binaries", "linux64", md.coSimulation.modelIdentifier + ".so")
    out = subprocess.run(["nm", "-D", "--defined-only", binary], check=True, capture_output=True, text=True)
    symbols = [line.split()[-1] for line in out.stdout.splitlines() if line.strip()]
    assert symbols and all(s.startswith("fmi2") for s in symbols), symbols
    assert "fmi2DoStep" in symbols and "fmi2GetDirectionalDerivative" in symbols
    dynamic = subprocess.run(["readelf", "-d", binary], check=True, capture_output=True, text=True).stdout
    # DT_RPATH, searched before LD_LIBRARY_PATH (DT_RUNPATH would come after it).
    assert "(RPATH)" in dynamic and "RUNPATH" not in dynamic and "[$ORIGIN]" in dynamic


def test_the_c_library_it_needs_is_that_of_the_documented_systems(test_fmu, tmp_path):
    """docs/fmu.md: the FMU loads where the C library is glibc 2.35 or later (Debian 12, Ubuntu
    22.04, RHEL 10): the newest symbol version any file in binaries/linux64 asks for is at most
    GLIBC_2.35 (the bundled libgcc_s of Debian 12 asks for it)."""
    folder = extract(str(test_fmu("driven_oscillator")), unzipdir=str(tmp_path / "unzipped"))
    binaries = os.path.join(folder, "binaries", "linux64")
    needed = set()
    for name in os.listdir(binaries):
        out = subprocess.run(["objdump", "-T", os.path.join(binaries, name)], check=True, capture_output=True,
                             text=True).stdout
        needed |= {tuple(int(n) for n in v.split(".")) for v in re.findall(r"\bGLIBC_([0-9.]+)\b", out)}
    assert needed and max(needed) <= (2, 35), max(needed)


def test_licences_of_everything_it_carries(test_fmu):
    """The binary comes with springmass's LICENSE, and every library in binaries/linux64 and the
    archive linked into the binary (SUNDIALS) with their Debian copyright file, in
    documentation/licenses/, named in its license.txt (the entry point FMI names). No GSL code is linked in (the FMU runs no analysis), so GSL's
    licence is not there: a binary that came to hold GSL's symbols would need it."""
    fmu = test_fmu("driven_oscillator")
    md = read_model_description(str(fmu))
    with zipfile.ZipFile(fmu) as archive:
        names = archive.namelist()
        readme = archive.read("documentation/licenses/license.txt").decode()
        listed = {}
        for line in readme.splitlines():
            fields = line.split()
            if len(fields) >= 2 and fields[-1].endswith(".txt"):
                listed[fields[0]] = fields[-1]
        libraries = [os.path.basename(n) for n in names
                     if n.startswith("binaries/linux64/") and not n.endswith("/")
                     and os.path.basename(n) != md.coSimulation.modelIdentifier + ".so"]
        assert libraries and "libcholmod.so.3" in libraries, names
        # SUNDIALS is linked in whole: none of its shared libraries travels beside the binary (Debian's
        # static sunlinsoldense and sunlinsolklu name shared matrices, which a linker without
        # --as-needed, as in the sanitizer builds, kept; CMakeLists.txt).
        assert not [n for n in libraries if n.startswith("libsundials")], libraries
        for name in libraries:
            assert name in listed, f"{name} has no licence in license.txt:\n{readme}"
            text = archive.read("documentation/licenses/" + listed[name]).decode(errors="replace")
            assert "Copyright" in text or "copyright" in text, (name, listed[name])
        assert "(linked in)" in readme and "no package found" not in readme, readme
        # springmass's own licence, the binary's, is the repository's LICENSE.
        assert listed.get("springmass") == "springmass.txt", readme
        with open(os.path.join(os.path.dirname(__file__), "..", "..", "LICENSE"), "rb") as f:
            assert archive.read("documentation/licenses/springmass.txt") == f.read()
        assert "libgsl" not in readme, readme
        binary = archive.read(f"binaries/linux64/{md.coSimulation.modelIdentifier}.so")
    with tempfile.NamedTemporaryFile(suffix=".so") as f:
        f.write(binary)
        f.flush()
        symbols = subprocess.run(["nm", f.name], check=True, capture_output=True, text=True).stdout
    assert "CVode" in symbols and "gsl_" not in symbols
    # The SUNDIALS code in the binary came from archives license.txt names: each function below is
    # defined in one of the archives beside it (SUNDIALS 6's libsundials_cvode.a holds the vector,
    # matrices and solvers too, but not KLU's solver; SUNDIALS 7's holds none of them).
    defined = set(re.findall(r" [tT] (\w+)$", symbols, re.MULTILINE))
    providers = {"CVodeCreate": ["cvode"], "SUNLinSol_KLU": ["sunlinsolklu"], "N_VNew_Serial": ["cvode", "nvecserial"],
                 "SUNDenseMatrix": ["cvode", "sunmatrixdense"], "SUNSparseMatrix": ["cvode", "sunmatrixsparse"],
                 "SUNLinSol_Dense": ["cvode", "sunlinsoldense"]}
    assert {"CVodeCreate", "SUNLinSol_KLU"} <= defined
    for function, archives in providers.items():
        if function in defined:
            assert any(f"libsundials_{a}.a" in listed for a in archives), (function, readme)
