"""Shared fixtures of the FMU tests: where the build is, and FMUs packaged on demand.

The build directory comes from SPRINGMASS_BUILD_DIR (ctest sets it), else <checkout>/build.
"""
import math
import os
import pathlib
import subprocess
import sys

import fmpy
import fmpy.fmi2
import pytest

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent.parent
sys.path.insert(0, str(HERE))
BUILD = pathlib.Path(os.environ.get("SPRINGMASS_BUILD_DIR", ROOT / "build"))
CLI = BUILD / "tools" / "springmass"
BUNDLED_FMUS = BUILD / "fmus"
MODELS = HERE / "models"
SANITIZED = os.environ.get("SPRINGMASS_SANITIZE", "") not in ("", "0", "OFF")

# fmpy 0.3.32's simulate_fmu gives a logger it is handed to its native message formatter
# (fmpy.logging.addLoggerProxy), which keeps it in one slot for the whole process; the default
# callbacks, which a call without a logger uses, log through that slot too, so a call without one
# after a call with one logs through a callback freed when that call returned (a segmentation fault
# when the FMU logs, seen with the files of this folder run in one process). Every simulate_fmu of
# the tests therefore gives a logger, by default fmpy's own printer, so that the slot holds the
# current call's.
_simulate_fmu = fmpy.simulate_fmu


def _simulate_fmu_with_a_logger(*args, **kwargs):
    if kwargs.get("logger") is None:
        kwargs["logger"] = fmpy.fmi2.printLogMessage
    return _simulate_fmu(*args, **kwargs)


fmpy.simulate_fmu = _simulate_fmu_with_a_logger


def undamped_response_to_held_forces(forces, h, x=0.7, v=0.0):
    """(x [m], v [m/s]) of the bob of models/driven_oscillator.json with d = 0 (2 kg on 50 N/m,
    rest length 0.5 m, anchor at 0) after forces[k] [N] held over the k-th of len(forces) steps of
    h [s] each, from x and v: exactly, each step a rotation about its rest point 0.5 + F / 50."""
    w = math.sqrt(50.0 / 2.0)
    c, s = math.cos(w * h), math.sin(w * h)
    for f in forces:
        rest = 0.5 + f / 50.0
        x, v = rest + (x - rest) * c + v / w * s, -(x - rest) * w * s + v * c
    return x, v


@pytest.fixture(scope="session")
def package(tmp_path_factory):
    """package(model_path, sets=()) -> path of an FMU made with `springmass fmu`, with `--set S` for
    each S of sets (made once per test run)."""
    out = tmp_path_factory.mktemp("fmus")
    made = {}

    def make(model, sets=()):
        model = pathlib.Path(model)
        key = (model, tuple(sets))
        if key not in made:
            fmu = out / (f"{model.stem}_set{len(made)}.fmu" if sets else f"{model.stem}.fmu")
            options = [word for s in sets for word in ("--set", s)]
            subprocess.run([str(CLI), "fmu", str(model), "-o", str(fmu), *options], check=True, capture_output=True)
            made[key] = fmu
        return made[key]

    return make


@pytest.fixture(scope="session")
def test_fmu(package):
    """test_fmu(name) -> FMU of tests/python/models/<name>.json."""
    return lambda name: package(MODELS / f"{name}.json")
