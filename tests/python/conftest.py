"""Shared fixtures of the FMU tests: where the build is, and FMUs packaged on demand.

The build directory comes from SPRINGMASS_BUILD_DIR (ctest sets it), else <checkout>/build.
"""
import os
import pathlib
import subprocess
import sys

import pytest

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent.parent
sys.path.insert(0, str(HERE))
BUILD = pathlib.Path(os.environ.get("SPRINGMASS_BUILD_DIR", ROOT / "build"))
CLI = BUILD / "tools" / "springmass"
BUNDLED_FMUS = BUILD / "fmus"
MODELS = HERE / "models"
SANITIZED = os.environ.get("SPRINGMASS_SANITIZE", "") not in ("", "0", "OFF")


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
