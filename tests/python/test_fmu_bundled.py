"""Every bundled model's FMU: valid for fmpy and the fmu-manipulation-toolbox checker, and
simulating it in fmpy gives what `springmass run` gives for the same file."""
import csv
import pathlib
import subprocess
import sys

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

from conftest import BUNDLED_FMUS, CLI, ROOT

MODELS = sorted((ROOT / "models").glob("*.json"))
FMUTOOL = pathlib.Path(sys.executable).parent / "fmutool"


def bundled(model):
    fmu = BUNDLED_FMUS / (model.stem + ".fmu")
    assert fmu.exists(), f"the build made no FMU of {model.name}"
    return fmu


@pytest.mark.parametrize("model", MODELS, ids=[m.stem for m in MODELS])
def test_bundled_fmu_is_valid(model):
    fmu = bundled(model)
    assert validate_fmu(str(fmu)) == []
    out = subprocess.run([str(FMUTOOL), "-input", str(fmu), "-check"], capture_output=True, text=True)
    text = out.stdout + out.stderr
    assert out.returncode == 0, text
    assert "No semantic error" in text and "compliant with FMI-2.0" in text, text
    md = read_model_description(str(fmu))
    assert md.guid and md.coSimulation.canGetAndSetFMUstate and md.coSimulation.providesDirectionalDerivative


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header = [h.strip() for h in rows[0]]
    data = np.array([[float(x) for x in r] for r in rows[1:] if r])
    return header, data


def run_available():
    out = subprocess.run([str(CLI), "run", "--help"], capture_output=True, text=True)
    return out.returncode == 0


@pytest.mark.parametrize("model", MODELS, ids=[m.stem for m in MODELS])
def test_bundled_fmu_matches_springmass_run(model, tmp_path):
    if not run_available():
        pytest.skip("`springmass run` is not available in this build")
    fmu = bundled(model)
    md = read_model_description(str(fmu))
    stop = float(md.defaultExperiment.stopTime)
    step = float(md.defaultExperiment.stepSize)
    # Short horizon for the big models: the comparison is about the interface, not endurance.
    stop = min(stop, 0.5)
    out = tmp_path / "run.csv"
    subprocess.run([str(CLI), "run", str(model), "--t-end", str(stop), "--output-interval", str(step),
                    "--output", str(out)], check=True, capture_output=True)
    header, data = read_csv(out)
    names = [v.name for v in md.modelVariables if v.causality == "output" and v.name in header]
    assert names, f"no common columns between the FMU's outputs and {header}"
    r = simulate_fmu(str(fmu), stop_time=stop, output_interval=step, output=names)
    n = min(len(r), len(data))
    assert np.allclose(r["time"][:n], data[:n, header.index("time")], atol=1e-9)
    for name in names:
        ours, theirs = r[name][:n], data[:n, header.index(name)]
        # Same library, same settings and the same output points; the FMU stops the solver at
        # every communication point while `run` may not, so they agree to the solver's
        # tolerance (default rtol 1e-6) relative to the signal's size, not bit for bit.
        scale = max(1.0, float(np.max(np.abs(theirs))))
        assert np.max(np.abs(ours - theirs)) <= 1e-3 * scale, name
