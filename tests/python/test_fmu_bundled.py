"""Every bundled model's FMU: valid for fmpy and the fmu-manipulation-toolbox checker, and
simulating it in fmpy gives what `springmass run` gives for the same file; a model packaged with
`springmass fmu --set` is the model with those values, as `springmass run --set` simulates it."""
import csv
import json
import os
import pathlib
import re
import subprocess
import sys
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.util import read_csv as read_csv_fmpy
from fmpy.validation import validate_fmu

from conftest import BUILD, BUNDLED_FMUS, CLI, MODELS as TEST_MODELS, ROOT
from fmu_helpers import fmu_guid, read_documentation

MODELS = sorted((ROOT / "models").glob("*.json"))
FMUTOOL = pathlib.Path(sys.executable).parent / "fmutool"


def bundled(model):
    fmu = BUNDLED_FMUS / (model.stem + ".fmu")
    assert fmu.exists(), f"the build made no FMU of {model.name}"
    return fmu


def check_valid(fmu):
    """fmpy's validation and the fmu-manipulation-toolbox checker find nothing wrong."""
    assert validate_fmu(str(fmu)) == []
    out = subprocess.run([str(FMUTOOL), "-input", str(fmu), "-check"], capture_output=True, text=True)
    text = out.stdout + out.stderr
    assert out.returncode == 0, text
    assert "No semantic error" in text and "compliant with FMI-2.0" in text, text


@pytest.mark.parametrize("model", MODELS, ids=[m.stem for m in MODELS])
def test_bundled_fmu_is_valid(model):
    fmu = bundled(model)
    check_valid(fmu)
    md = read_model_description(str(fmu))
    assert md.guid and md.coSimulation.canGetAndSetFMUstate and md.coSimulation.providesDirectionalDerivative


def documented_rows(md, causality, variability=None, with_variability=False):
    """The rows documentation/index.html must have for these variables: value reference, name,
    variability (parameters), unit, start value (not outputs) and description as
    modelDescription.xml has them."""
    rows = []
    for v in md.modelVariables:
        if v.causality != causality or (variability and v.variability != variability):
            continue
        row = [str(v.valueReference), v.name] + ([v.variability] if with_variability else [])
        start = [] if causality == "output" else ["" if v.start is None else str(v.start)]
        rows.append(row + [v.unit or ""] + start + [v.description])
    return rows


@pytest.mark.parametrize("model", MODELS, ids=[m.stem for m in MODELS])
def test_bundled_fmu_documents_its_variables(model):
    # documentation/index.html is written from the FMU's variable table: every input, output,
    # parameter and constant with the value reference, unit, start value and description of
    # modelDescription.xml, the particles' locals as the range they fill, the default experiment,
    # and a link to the licences' entry point that the archive holds.
    fmu = bundled(model)
    md = read_model_description(str(fmu))
    doc = read_documentation(fmu)
    assert doc.title == md.modelName
    assert doc.paragraphs[""][0] == md.description
    assert md.guid in doc.paragraphs[""][1] and md.coSimulation.modelIdentifier in doc.paragraphs[""][1]
    assert doc.tables.get("inputs", []) == documented_rows(md, "input")
    if doc.tables.get("inputs"):  # held, or extrapolated with their derivatives (canInterpolateInputs)
        assert md.coSimulation.canInterpolateInputs
        assert "fmi2SetRealInputDerivatives" in doc.paragraphs["inputs"][0], doc.paragraphs["inputs"]
    assert doc.tables["outputs"] == documented_rows(md, "output")
    assert doc.tables["parameters"] == documented_rows(md, "parameter", with_variability=True)
    assert doc.tables.get("constants", []) == documented_rows(md, "local", "constant")
    listed = sum(len(rows) for rows in doc.tables.values())
    particles = [v for v in md.modelVariables if v.name.startswith("p[")]
    assert listed + len(particles) == len(md.modelVariables)
    if particles:
        first, last = particles[0], particles[-1]
        assert [int(v.valueReference) for v in particles] == list(range(first.valueReference, last.valueReference + 1))
        assert len(particles) % 6 == 0 and last.name == f"p[{len(particles) // 6 - 1}].vz"
        sentence = doc.paragraphs["particles"][0]
        assert f"{first.name} … {last.name}, value references {first.valueReference} to {last.valueReference}" \
            in sentence, sentence
        assert f"at value references {first.valueReference} + 6 i to {first.valueReference + 5} + 6 i" in sentence
    with zipfile.ZipFile(fmu) as archive:
        names = set(archive.namelist())
        page = archive.read("documentation/index.html").decode("utf-8")
    experiment = re.search(r"from 0 s to (\S+) s in communication steps of (\S+) s, relative tolerance (\S+) ", page)
    assert experiment, "no default experiment in the page"
    de = md.defaultExperiment
    assert list(experiment.groups()) == [de.stopTime, de.stepSize, de.tolerance]  # the XML's text
    assert doc.links == ["licenses/license.txt"] and "documentation/licenses/license.txt" in names


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header = [h.strip() for h in rows[0]]
    data = np.array([[float(x) for x in r] for r in rows[1:] if r])
    return header, data


def run_available():
    out = subprocess.run([str(CLI), "run", "--help"], capture_output=True, text=True)
    return out.returncode == 0


# Given the stop time, the FMU interpolates its outputs from CVODE's steps as `springmass run`
# does its rows; without it, every communication step ends an internal step, as
# `springmass run --stop-at-outputs` does at every row.
@pytest.mark.parametrize("set_stop_time", [True, False], ids=["stop time", "no stop time"])
@pytest.mark.parametrize("model", MODELS, ids=[m.stem for m in MODELS])
def test_bundled_fmu_matches_springmass_run(model, set_stop_time, tmp_path):
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
                    "--output", str(out)] + ([] if set_stop_time else ["--stop-at-outputs"]), check=True,
                   capture_output=True)
    header, data = read_csv(out)
    names = [v.name for v in md.modelVariables if v.causality == "output" and v.name in header]
    assert names, f"no common columns between the FMU's outputs and {header}"
    r = simulate_fmu(str(fmu), stop_time=stop, output_interval=step, output=names, set_stop_time=set_stop_time)
    assert len(r) == len(data)
    assert np.allclose(r["time"], data[:, header.index("time")], atol=1e-9)
    for name in names:
        ours, theirs = r[name], data[:, header.index(name)]
        # Same library, same settings, the same output points and the same steps: the same
        # numbers (measured: equal bit for bit on every bundled model; the CSV's shortest
        # round-trip text reads back exactly), where interpolating and ending a step at every
        # point differ by up to 1e-6. 1e-9 of the signal's size.
        scale = max(1.0, float(np.max(np.abs(theirs))))
        assert np.max(np.abs(ours - theirs)) <= 1e-9 * scale, name


def read_obj(path):
    """The vertices and triangles of an OBJ file as docs/model-format.md reads them: each `v x y z`,
    and each face `f` (indices from 1, a texture or normal index after a slash dropped) cut into a
    fan of triangles from its first vertex, with indices from 0. Enough for the bundled files
    (positive indices, no continued lines)."""
    vertices, triangles = [], []
    for line in path.read_text().splitlines():
        words = line.split("#", 1)[0].split()
        if words and words[0] == "v":
            vertices.append([float(c) for c in words[1:4]])
        elif words and words[0] == "f":
            face = [int(word.split("/")[0]) - 1 for word in words[1:]]
            triangles += [[face[0], face[k], face[k + 1]] for k in range(1, len(face) - 1)]
    return vertices, triangles


@pytest.mark.parametrize("model", MODELS, ids=[m.stem for m in MODELS])
def test_bundled_fmu_carries_its_model_file_alone_and_its_guid_is_the_file_hash(model):
    # Packaged without --set: resources/model.json is the file byte for byte, there is no
    # resources/parameters.txt (beside it only the reference result, which the GUID does not hash),
    # and the GUID is the hash of the file alone, as before --set existed. A model whose meshes read
    # OBJ files packs the file with each such mesh's vertices and triangles, as read from its OBJ
    # file, in place of its "file" (the FMU needs no OBJ file), and the GUID hashes what it packs.
    fmu = bundled(model)
    with zipfile.ZipFile(fmu) as z:
        assert [n for n in z.namelist() if n.startswith("resources/") and not n.endswith("/")] == \
            ["resources/model.json", "resources/reference.csv"]
        packed = z.read("resources/model.json")
    expected = json.loads(model.read_bytes())
    meshes = [s for s in expected.get("structures", []) if "file" in s]
    if not meshes:
        assert packed == model.read_bytes()
    for mesh in meshes:
        mesh["vertices"], mesh["triangles"] = read_obj(model.parent / mesh.pop("file"))
    assert json.loads(packed) == expected
    assert read_model_description(str(fmu)).guid == fmu_guid(packed)


def mesh_files(model):
    """The OBJ files a model file's meshes read ("file", relative to the model's folder)."""
    return [(model.parent / s["file"]).resolve() for s in json.loads(model.read_bytes()).get("structures", [])
            if "file" in s]


def build_inputs(output):
    """The files the build makes one of its outputs from, as Ninja has them (`ninja -t query`); None
    for a build of another generator."""
    cache = {}
    for line in (BUILD / "CMakeCache.txt").read_text().splitlines():
        if "=" in line and not line.startswith(("#", "//")):
            key, value = line.split("=", 1)
            cache[key.split(":")[0]] = value
    if cache.get("CMAKE_GENERATOR") != "Ninja":
        return None
    out = subprocess.run([cache["CMAKE_MAKE_PROGRAM"], "-C", str(BUILD), "-t", "query",
                          os.path.relpath(output, BUILD)], capture_output=True, text=True, check=True)
    listed = out.stdout.split("  input:", 1)[1].split("  outputs:", 1)[0].splitlines()[1:]
    return {(BUILD / line.strip().lstrip("|").strip()).resolve() for line in listed}


@pytest.mark.parametrize("model", [m for m in MODELS if mesh_files(m)],
                         ids=[m.stem for m in MODELS if mesh_files(m)])
def test_bundled_fmu_is_packed_again_when_an_obj_file_its_model_reads_changes(model):
    # The FMU carries the vertices and triangles of the OBJ files its model's meshes read: the build
    # makes it from them as from the model file, so that an edited OBJ file gives a new FMU, not
    # the one packed from the file as it was.
    inputs = build_inputs(bundled(model))
    if inputs is None:
        pytest.skip("the build's dependencies are read from Ninja's")
    assert model.resolve() in inputs
    for obj in mesh_files(model):
        assert obj in inputs, f"{bundled(model).name} is not made again when {obj.name} changes"


def quantity(name, outputs):
    """The outputs of the quantity an output is a component of: a port's position, velocity or
    force vector (`tip.x` -> `tip.x tip.y tip.z`), or the energies."""
    if name.startswith("energy."):
        return [o for o in outputs if o.startswith("energy.")]
    port, field = name.rsplit(".", 1)
    return [f"{port}.{field[:-1]}{axis}" for axis in "xyz"]


# The tolerances tests/references/update.sh computes the reference results at.
REFERENCE_TOLERANCES = {"solver.rtol": 1e-10, "solver.atol_position": 1e-12, "solver.atol_velocity": 1e-12}


@pytest.mark.parametrize("model", MODELS, ids=[m.stem for m in MODELS])
def test_bundled_fmu_carries_its_reference_result_and_reproduces_it(model, tmp_path):
    # A bundled model's FMU holds its reference result for regression checks: tests/references/
    # <model>.csv without the line of the command that made it, a CSV that fmpy reads with the
    # FMU's outputs as its columns. Simulated at the reference's tolerances, the FMU gives it back.
    fmu = bundled(model)
    command, table = (ROOT / "tests" / "references" / (model.stem + ".csv")).read_bytes().split(b"\n", 1)
    assert command.startswith(b"# springmass run")
    with zipfile.ZipFile(fmu) as z:
        packed = z.read("resources/reference.csv")
    assert packed == table
    (tmp_path / "reference.csv").write_bytes(packed)
    reference = read_csv_fmpy(tmp_path / "reference.csv")
    md = read_model_description(str(fmu))
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    assert list(reference.dtype.names) == ["time"] + outputs
    # Short horizon for the big models, as above: the rows up to 0.5 s.
    rows = reference[reference["time"] <= 0.5]
    step = float(rows["time"][1] - rows["time"][0])
    r = simulate_fmu(str(fmu), stop_time=float(rows["time"][-1]), output_interval=step, output=outputs,
                     start_values=REFERENCE_TOLERANCES)
    assert len(r) == len(rows) and np.allclose(r["time"], rows["time"], rtol=0, atol=1e-12)
    for name in outputs:
        # The same library and tolerances as the run that wrote the reference, over a shorter
        # horizon (other first steps): the two differ by the global error at rtol 1e-10, which a
        # run at rtol 1e-12 puts at up to 5e-8 of a quantity's scale (tests/test_references.c;
        # measured here: 1.3e-9, the hanging rope's middle.vx). 1e-6 of the largest component
        # plus 1e-9, as that test allows the library, catches a changed model or solver. The scale
        # is the quantity's, as there: the largest of the vector's components or of the energies.
        scale = max(float(np.max(np.abs(rows[other]))) for other in quantity(name, outputs))
        assert np.max(np.abs(r[name] - rows[name])) <= 1e-6 * scale + 1e-9, name


# hanging_rope_n.json: a rope of n = 10 segments pinned at rope[0], E and c tunable, T the stop time.
ROPE = TEST_MODELS / "hanging_rope_n.json"
ROPE_SETS = ("n=40", "E=3000", "T=0.3")


def test_set_values_package_the_model_as_if_the_file_gave_them(package, tmp_path):
    # n = 40 segments: 41 particles in the variable table, n a constant of 40, the tunable E's start
    # value 3000 and the DefaultExperiment's stop time T = 0.3 s. The model file travels as it is,
    # the values beside it, and the GUID hashes both.
    plain, changed = package(ROPE), package(ROPE, ROPE_SETS)
    check_valid(changed)
    text = ROPE.read_bytes()
    with zipfile.ZipFile(changed) as z:
        assert z.read("resources/model.json") == text
        parameters = z.read("resources/parameters.txt")
    assert parameters == b"n=40\nE=3000\nT=0.3\n"
    md, md_plain = read_model_description(str(changed)), read_model_description(str(plain))
    assert md.guid == fmu_guid(text, parameters)
    assert md_plain.guid == fmu_guid(text) != md.guid
    v = {x.name: x for x in md.modelVariables}
    assert (v["n"].causality, v["n"].variability, v["n"].start) == ("local", "constant", "40")
    assert (v["E"].causality, v["E"].variability, v["E"].start) == ("parameter", "tunable", "3000")
    assert float(md.defaultExperiment.stopTime) == 0.3
    assert "p[40].z" in v and "p[41].z" not in v
    assert {x.name for x in md_plain.modelVariables} >= {"p[10].z"} and "p[11].z" not in \
        {x.name for x in md_plain.modelVariables}

    # The same as `springmass run --set` of the file, output point for output point: one library,
    # one model, the same steps, the outputs interpolated from them (fmpy gives the stop time)
    # (measured: equal bit for bit; E = 2000 instead of 3000 differs by up to 3e-2).
    out = tmp_path / "run.csv"
    subprocess.run([str(CLI), "run", str(ROPE), *(w for s in ROPE_SETS for w in ("--set", s)), "--positions",
                    "--output-interval", "0.01", "-q", "-o", str(out)], check=True, capture_output=True)
    header, data = read_csv(out)
    columns = {f"p[{i}].{c}": f"particle.rope[{i}].{c}" for i in range(41) for c in "xyz"}
    assert "particle.rope[40].z" in header and "particle.rope[41].z" not in header
    columns.update({name: name for name in ("near.x", "near.z", "energy.kinetic", "energy.elastic",
                                            "energy.gravity", "energy.dissipated")})
    r = simulate_fmu(str(changed), output_interval=0.01, output=list(columns))  # to the default stop time
    assert len(r) == len(data) == 31 and r["time"][-1] == pytest.approx(0.3)
    for name, column in columns.items():
        theirs = data[:, header.index(column)]
        assert np.max(np.abs(r[name] - theirs)) <= 1e-9 * max(1.0, float(np.max(np.abs(theirs)))), name


def test_set_values_the_file_has_change_nothing(package):
    # n = 10 is the file's own value: the FMU is the one packaged without --set.
    plain, same = package(ROPE), package(ROPE, ("n=10", "E=2000"))
    with zipfile.ZipFile(plain) as a, zipfile.ZipFile(same) as b:
        assert a.namelist() == b.namelist()
        assert a.read("modelDescription.xml") == b.read("modelDescription.xml")


def test_a_port_named_by_a_parameter_expression_follows_the_grid(package):
    # The trampoline's force port is membrane[n/2, n/2]: packaged with n = 15 it is particle
    # 7 * 15 + 7 = 112, the centre (0.5, 0.5, 0) m, and n is a constant of the FMU, as a count is.
    # Its outputs are that particle's own variables, step for step (the same numbers: one state).
    trampoline = ROOT / "models" / "trampoline.json"
    fmu = package(trampoline, ("n=15",))
    check_valid(fmu)
    md = read_model_description(str(fmu))
    v = {x.name: x for x in md.modelVariables}
    assert (v["n"].causality, v["n"].variability, v["n"].start) == ("local", "constant", "15")
    assert v["n"].description == (
        "model-file parameter n (constant: sets the model's structure (a count and which particle a "
        "reference names), fixed at packaging)")
    # The documentation's constants table says the same of what makes a parameter a constant.
    assert "which particle a reference names" in read_documentation(fmu).paragraphs["constants"][0]
    assert "membrane[7,7]" in v["centre.z"].description
    names = ["centre.x", "centre.y", "centre.z", "p[112].x", "p[112].y", "p[112].z"]
    r = simulate_fmu(str(fmu), stop_time=0.1, output_interval=0.01, output=names)
    assert (r["centre.x"][0], r["centre.y"][0], r["centre.z"][0]) == (0.5, 0.5, 0.0)
    for c in "xyz":
        assert np.array_equal(r[f"centre.{c}"], r[f"p[112].{c}"])
    # Dropped from flat, the centre falls: by g t^2 / 2 = 0.049 m at 0.1 s if free, less as the
    # membrane catches it.
    assert -0.049 < r["centre.z"][-1] < -0.005
