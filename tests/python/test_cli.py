"""The `springmass` tool as a user meets it: its exit statuses, the rows and columns of `run`,
the ParaView series, and what `statics`, `modes`, `check` and `fmu` print and write, each checked
against the model's physics or against another of the tool's own outputs (the CSV against the
VTK files, statics against the modes about its rest shape), never against a stored copy of the
output."""
import csv
import json
import math
import os
import re
import resource
import shutil
import signal
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest

from conftest import CLI, ROOT, SANITIZED, undamped_response_to_held_forces
from fmu_helpers import read_documentation

MODELS = ROOT / "models"
# Set by ctest when the build has the FMU runtime that `springmass fmu` packs.
HAS_FMU = os.environ.get("SPRINGMASS_HAS_FMU") == "1"


def cli(*args, status=0, cwd=None, env=None):
    """Runs the tool (in the environment env, if given); asserts its exit status; returns the
    finished process (text). Every call here takes well under a second: a minute means the tool
    hangs (e.g. a row limit not applied)."""
    out = subprocess.run([str(CLI), *map(str, args)], capture_output=True, text=True, cwd=cwd, env=env, timeout=60)
    assert out.returncode == status, f"springmass {' '.join(map(str, args))}: exit {out.returncode}\n{out.stderr}"
    return out


def read_csv(path):
    """(header, rows as a float array) of a CSV with a header line; a `name` column (statics,
    modes) reads as NaN."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    named = rows[0].index("name") if "name" in rows[0] else -1
    return rows[0], np.array([[math.nan if i == named else float(x) for i, x in enumerate(r)] for r in rows[1:]])


def run_csv(tmp_path, model, *options, name="run.csv"):
    path = tmp_path / name
    cli("run", model, "-q", "-o", path, *options)
    return read_csv(path)


def vtk_sections(path):
    """POINTS (n x 3), LINES (pairs), VECTORS of the point data (name -> n x 3) and SCALARS of the
    cell data (name -> one per line) of a legacy VTK polydata file."""
    words = open(path).read().split("\n")
    points, lines, vectors, scalars = None, [], {}, {}
    i = 0
    while i < len(words):
        fields = words[i].split()
        if fields[:1] == ["POINTS"]:
            n = int(fields[1])
            points = np.array([[float(v) for v in words[i + 1 + k].split()] for k in range(n)])
            i += n
        elif fields[:1] == ["LINES"]:
            lines = [tuple(int(v) for v in words[i + 1 + k].split()[1:]) for k in range(int(fields[1]))]
            # The legacy format's size is the count of integers that follow: 3 per line of two points.
            assert int(fields[2]) == 3 * len(lines), words[i]
            i += len(lines)
        elif fields[:1] == ["VECTORS"]:
            vectors[fields[1]] = np.array([[float(v) for v in words[i + 1 + k].split()] for k in range(len(points))])
            i += len(points)
        elif fields[:1] == ["CELL_DATA"]:
            assert int(fields[1]) == len(lines), words[i]
        elif fields[:1] == ["SCALARS"]:
            assert fields[2:] == ["double", "1"] and words[i + 1] == "LOOKUP_TABLE default", words[i:i + 2]
            scalars[fields[1]] = np.array([float(words[i + 2 + k]) for k in range(len(lines))])
            i += 1 + len(lines)
        i += 1
    return points, lines, vectors, scalars


def number_after(text, label):
    """The first number after `label` in text."""
    match = re.search(re.escape(label) + r"\s*([-+0-9.eE]+)", text)
    assert match, f"no '{label}' in:\n{text}"
    return float(match.group(1))


# --- Exit statuses -----------------------------------------------------------------------------

def test_usage_errors_exit_with_2_and_help_goes_to_standard_output(tmp_path):
    osc = MODELS / "oscillator.json"
    cli(status=2)
    assert "unknown command 'frob'" in cli("frob", status=2).stderr
    for args in (["--help"], ["help"], ["-h"]):
        assert cli(*args).stdout.startswith("usage:")
    assert re.fullmatch(r"springmass \d+\.\d+\.\d+\n", cli("--version").stdout)
    for command in ("run", "check", "statics", "modes") + (("fmu",) if HAS_FMU else ()):
        out = cli(command, "--help")
        assert out.stdout.startswith("usage: springmass " + command) and out.stderr == ""
        # `springmass help COMMAND` prints the same help (git's convention).
        assert cli("help", command).stdout == out.stdout
    assert "unknown command 'frob'" in cli("help", "frob", status=2).stderr
    assert "one command at most" in cli("help", "run", "check", status=2).stderr
    if not HAS_FMU:
        # A build without FMUs has the command, which refuses whatever it is given: it cannot run.
        for args in (["--help"], [], [osc, "-o", tmp_path / "x.fmu"]):
            out = cli("fmu", *args, status=1)
            assert "this build has no FMU support" in out.stderr and out.stdout == "", out.stderr
        assert list(tmp_path.iterdir()) == []
    usage_errors = [
        ["run"], ["run", osc, osc], ["run", osc, "--solver", "x"], ["run", osc, "--method", "x"],
        ["run", osc, "--max-steps", "1.5"], ["run", osc, "--t-end", "nan"], ["run", osc, "--set", "k"],
        ["check"], ["statics", osc, osc], ["statics", osc, "--max-iterations", "0"],
        ["statics", osc, "--solver", "x"], ["modes", osc, osc], ["modes", osc, "-n", "-1"],
        ["modes", osc, "--steps-per-period", "0.5"], ["modes", osc, "--solver", "x"],
    ]
    if HAS_FMU:
        usage_errors += [["fmu", osc], ["fmu", osc, osc, "-o", tmp_path / "x.fmu"]]
    for args in usage_errors:
        out = cli(*args, status=2)
        assert out.stderr.startswith("springmass"), (args, out.stderr)
        # A value refused says why in one line; an unknown option, a missing value or model file
        # brings the usage after the message, in every command alike.
        with_usage = len(args) == 1 or args[-1] == osc or args[-1] == tmp_path / "x.fmu"
        assert ("\nusage: springmass " in out.stderr) == with_usage, (args, out.stderr)
        assert with_usage or out.stderr.count("\n") == 1, (args, out.stderr)
    for command in ("run", "statics", "modes") + (("fmu",) if HAS_FMU else ()):
        out = cli(command, osc, "--frobnicate", status=2)
        assert "unknown option or missing value: --frobnicate\n\nusage: springmass " + command in out.stderr
    assert not (tmp_path / "x.fmu").exists()
    # Bad values are errors of the model (1), not of the usage.
    assert 'no parameter named "nosuch"' in cli("run", osc, "--set", "nosuch=1", status=1).stderr


# --- run ---------------------------------------------------------------------------------------

def test_rows_run_from_zero_to_exactly_the_end_time(tmp_path):
    # 2.1 / 0.3 = 7.000000000000001 in doubles: the rows are 0, 0.3, ..., 1.8 and then 2.1,
    # not an extra row or a repeated time.
    assert 2.1 / 0.3 > 7
    _, rows = run_csv(tmp_path, MODELS / "oscillator.json", "--t-end", 2.1, "--output-interval", 0.3)
    assert len(rows) == 8 and rows[-1, 0] == 2.1
    assert np.all(np.diff(rows[:, 0]) > 0)
    np.testing.assert_allclose(rows[:7, 0], 0.3 * np.arange(7), rtol=0, atol=1e-15)
    # A last interval shorter than the others: 0, 0.3, 0.6, 0.9, 1.0.
    _, rows = run_csv(tmp_path, MODELS / "oscillator.json", "--t-end", 1.0, "--output-interval", 0.3)
    assert list(rows[:, 0]) == [0.0, 0.3, 0.6, 0.8999999999999999, 1.0]


def test_run_messages_give_the_times_of_rows_as_the_csv_writes_them(tmp_path):
    # The summary names the end time, which is the last row's, with all of its eight digits.
    path = tmp_path / "end.csv"
    summary = cli("run", MODELS / "oscillator.json", "--t-end", "1.2345678", "-o", path).stderr
    assert re.search(r"^springmass run: oscillator to t = 1\.2345678 s with ", summary, re.M), summary
    with open(path, newline="") as f:
        assert list(csv.reader(f))[-1][0] == "1.2345678"
    # A force beyond what the solver can follow from 0.35 s on stops the run after the row at
    # 3 x 0.1 = 0.30000000000000004 s (in doubles); the message names that row as the CSV does.
    signals = tmp_path / "blow.csv"
    signals.write_text("time,tip.fx\n0,0\n0.35,0\n0.35,1e308\n")
    path = tmp_path / "stopped.csv"
    out = cli("run", MODELS / "oscillator.json", "-q", "--input", signals, "--output-interval", 0.1,
              "--t-end", 1, "-o", path, status=1)
    with open(path, newline="") as f:
        last = list(csv.reader(f))[-1][0]
    assert last == "0.30000000000000004"
    assert out.stderr.splitlines()[-1] == f"springmass run: stopped; the outputs hold the rows up to t = {last} s"


def test_default_output_is_the_model_name_with_the_files_settings(tmp_path):
    cli("run", MODELS / "oscillator.json", "-q", cwd=tmp_path)
    _, rows = read_csv(tmp_path / "oscillator.csv")
    # The file's stop time 5 s and output interval 0.01 s: 501 rows.
    assert len(rows) == 501 and rows[-1, 0] == 5.0


def test_more_rows_than_the_limit_are_refused_before_anything_is_written(tmp_path):
    # 2e9 rows, twice the limit of 1e9. Written to /dev/null: a tool that took them would write
    # until cli()'s timeout, not fill the disk.
    out = cli("run", MODELS / "oscillator.json", "--t-end", 200, "--output-interval", 1e-7, "-o", "/dev/null", status=1)
    assert out.stderr == ("springmass run: 200 s (--t-end) / 1e-07 s (--output-interval) would make more than "
                          "1e+09 output rows: give a larger interval\n"), out.stderr
    # The oscillator's file gives 5 s: the message says that the end time came from it.
    out = cli("run", MODELS / "oscillator.json", "--output-interval", 1e-9, "-o", "/dev/null", status=1)
    assert out.stderr.startswith("springmass run: 5 s (the model's simulation.stop_time) / 1e-09 s (--output-interval)"), out.stderr
    out = cli("run", MODELS / "oscillator.json", "--t-end", 1e8, "-o", "/dev/null", status=1)
    assert out.stderr.startswith("springmass run: 100000000 s (--t-end) / 0.01 s (the model's simulation.output_interval)"), out.stderr
    # Far beyond the limit, with files asked for: none is created.
    cli("run", MODELS / "oscillator.json", "--t-end", 1e3, "--output-interval", 1e-300,
        "-o", tmp_path / "many.csv", "--vtk", tmp_path / "vtk", status=1)
    assert not (tmp_path / "many.csv").exists() and not (tmp_path / "vtk").exists()


def test_port_columns_are_named_by_kind_and_carry_the_port_quantities(tmp_path):
    header, rows = run_csv(tmp_path, MODELS / "two_mass_chain.json", "--t-end", 1, "--positions")
    quantities = {"motion": ["fx", "fy", "fz"], "probe": ["x", "y", "z", "vx", "vy", "vz"]}
    quantities["force"] = quantities["probe"]
    expected = ["time"]
    for port, kind in (("base", "motion"), ("m1", "probe"), ("m2", "force")):
        expected += [f"{port}.{q}" for q in quantities[kind]]
    expected += ["energy.kinetic", "energy.elastic", "energy.gravity", "energy.dissipated", "energy.input"]
    expected += [f"particle.{p}.{c}" for p in ("base", "m1", "m2") for c in "xyz"]
    assert header == expected
    col = {name: rows[:, i] for i, name in enumerate(header)}
    # The motion port's force is what the first spring exerts on the base: along +x,
    # k1 (x1 - l0) + d1 v1 (k1 = 40 N/m, l0 = 1 m, d1 = 0.2 N s/m, the base at rest at 0). Every
    # number is printed to round trip, so only the rounding of this sum remains (1e-12 N).
    np.testing.assert_allclose(col["base.fx"], 40 * (col["m1.x"] - 1) + 0.2 * col["m1.vx"], rtol=0, atol=1e-12)
    # The probe and the force port read their particles' positions.
    assert np.array_equal(col["m1.x"], col["particle.m1.x"]) and np.array_equal(col["m2.x"], col["particle.m2.x"])
    # Kinetic energy from the port velocities (m1 = 1 kg, m2 = 0.5 kg), to rounding.
    kinetic = 0.5 * 1.0 * col["m1.vx"] ** 2 + 0.5 * 0.5 * col["m2.vx"] ** 2
    np.testing.assert_allclose(col["energy.kinetic"], kinetic, rtol=1e-12, atol=1e-15)


def test_names_with_quotes_and_commas_are_quoted_in_the_header(tmp_path):
    # RFC 4180: a field holding a comma or a quote is quoted, its quotes doubled.
    model = tmp_path / "names.json"
    model.write_text('{"springmass": 1, "name": "names", "particles": [{"name": "a\\"b", "position": [0, 0, 0]},'
                     ' {"name": "c,d", "position": [1, 0, 0]}], "gravity": [0, 0, 0]}')
    cli("run", model, "-q", "--t-end", 0.01, "--positions", "-o", tmp_path / "names.csv")
    header = (tmp_path / "names.csv").read_text().split("\n")[0]
    assert header.endswith(',"particle.a""b.x","particle.a""b.y","particle.a""b.z",'
                           '"particle.c,d.x","particle.c,d.y","particle.c,d.z"'), header
    assert read_csv(tmp_path / "names.csv")[0][-6:-3] == ['particle.a"b.x', 'particle.a"b.y', 'particle.a"b.z']


def test_unnamed_particles_are_named_in_the_header_as_the_readme_says(tmp_path):
    # README: a particle without a name is p[i] in the --positions columns, primed when a particle
    # has that name (particle 0 is unnamed, particle 1 is named "p[0]").
    model = tmp_path / "unnamed.json"
    model.write_text('{"springmass": 1, "name": "unnamed", "particles": [{"position": [0, 0, 0]},'
                     ' {"name": "p[0]", "position": [1, 0, 0]}, {"position": [2, 0, 0]}], "gravity": [0, 0, 0]}')
    cli("run", model, "-q", "--t-end", 0.01, "--positions", "-o", tmp_path / "unnamed.csv")
    header = read_csv(tmp_path / "unnamed.csv")[0]
    assert header[-9:] == ["particle.p[0]'.x", "particle.p[0]'.y", "particle.p[0]'.z", "particle.p[0].x",
                           "particle.p[0].y", "particle.p[0].z", "particle.p[2].x", "particle.p[2].y",
                           "particle.p[2].z"], header


def test_options_take_effect(tmp_path):
    osc = MODELS / "oscillator.json"
    base = ["--t-end", 2]
    _, default = run_csv(tmp_path, osc, *base, name="default.csv")
    # The last --set of a parameter wins.
    _, k80 = run_csv(tmp_path, osc, *base, "--set", "k=80", name="k80.csv")
    _, k1_k80 = run_csv(tmp_path, osc, *base, "--set", "k=1", "--set", "k=80", name="k1_k80.csv")
    assert np.array_equal(k80, k1_k80) and not np.array_equal(k80, default)
    # Looser tolerances give another (still accurate) trajectory; each option alone changes it.
    for option in (["--rtol", 1e-3], ["--atol-position", 1e-3], ["--atol-velocity", 1e-2], ["--atol", 1e-5]):
        _, loose = run_csv(tmp_path, osc, *base, *option, name="loose.csv")
        assert not np.array_equal(loose, default), option
        # tip.x: the file's tolerances keep it within ~1e-8 m. The rows are interpolated from the
        # solver's steps, which the 0.01 s rows no longer cut short: each step errs by about the
        # tolerance and the errors add up over the two periods (measured: 7.6e-4 m at rtol 1e-3,
        # 1.6e-4 m at atol 1e-5; 1.1e-2 m at atol 1e-3, which is why that one is not used).
        # 2e-3 m, a fiftieth of the amplitude, bounds them with a margin of 2.5 (the step sequences,
        # and with them the largest, move with the last bits of the error estimates).
        np.testing.assert_allclose(loose[:, 1], default[:, 1], rtol=0, atol=2e-3)
    # Adams and every linear solver integrate the same equations: the bob's position agrees
    # within what the file's tolerances (rtol 1e-8, atol 1e-10 m) allow over 2 s, 1e-6 m.
    for option in (["--method", "adams"], ["--solver", "klu"], ["--solver", "pcg"], ["--solver", "cholmod"]):
        path = tmp_path / "other.csv"
        stats = cli("run", osc, *base, "-o", path, *option).stderr
        expected = "Adams" if option[1] == "adams" else "solver " + option[1]
        assert expected in stats, stats
        _, other = read_csv(path)
        np.testing.assert_allclose(other[:, 1], default[:, 1], rtol=0, atol=1e-6)
    # The definiteness-preserving Jacobian changes Newton's iterates, not the equations. The
    # oscillator moves along its spring, where both Jacobians agree; the swinging rope turns its
    # springs. At rtol 1e-9 the two runs of its tip agree to what the tolerances allow over
    # 0.5 s of swing (measured 2.6e-9 m, its velocity 1.1e-7 m/s): 1e-5 m.
    rope = [MODELS / "hanging_rope.json", "--t-end", 0.5, "--solver", "klu", "--rtol", 1e-9, "--atol", 1e-11]
    _, exact = run_csv(tmp_path, *rope, "--jacobian", "exact", name="exact.csv")
    _, definite = run_csv(tmp_path, *rope, "--jacobian", "definite", name="definite.csv")
    assert not np.array_equal(definite, exact)
    np.testing.assert_allclose(definite[:, 1:7], exact[:, 1:7], rtol=0, atol=1e-5)
    # BDF's stability limit detection (on by default) lets the hanging rope of 10 segments with
    # mass damping 1 1/s take longer steps as it settles: 13 090 steps over 100 s with it, 24 868
    # without (measured). Either way its tip hangs within 1e-10 m of the rest shape statics finds
    # after those 100 s, which decay every mode at least like exp(-t / 2) (measured 1.8e-13 m and
    # 3e-14 m; 1e-10 m is a hundredth of the position tolerance, 1e-8 m).
    settle = [MODELS / "hanging_rope.json", "--set", "alpha=1", "--set", "n=10"]
    cli("statics", *settle, "-q", "-o", tmp_path / "rest.csv")
    _, rest = read_csv(tmp_path / "rest.csv")
    steps = {}
    for detection in ("on", "off"):
        path = tmp_path / f"settle_{detection}.csv"
        stats = cli("run", *settle, "--t-end", 100, "--output-interval", 100, "-o", path,
                    "--stability-limit-detection", detection).stderr
        steps[detection] = int(stats.split(" steps,")[0].split()[-1])
        _, settled = read_csv(path)
        np.testing.assert_allclose(settled[-1, 1:4], rest[10, 2:5], rtol=0, atol=1e-10)
    assert steps["off"] >= 1.5 * steps["on"], steps
    cli("run", *settle, "--stability-limit-detection", "yes", status=2)
    # Internal steps of at most 1 ms take at least 2000 steps over 2 s.
    stats = cli("run", osc, *base, "-o", tmp_path / "short.csv", "--max-step", 1e-3).stderr
    assert int(stats.split(" steps,")[0].split()[-1]) >= 2000, stats
    _, short = read_csv(tmp_path / "short.csv")
    np.testing.assert_allclose(short[:, 1], default[:, 1], rtol=0, atol=1e-6)
    # One internal step per output interval is not enough for a second of the oscillator.
    # The run ends there, and says so with the time of its last row, which the CSV ends with
    # (the library's own message says that a caller's next advance could go on).
    out = cli("run", osc, "-q", "-o", tmp_path / "few.csv", "--max-steps", 1, "--output-interval", 1, status=1)
    assert "steps" in out.stderr
    assert out.stderr.splitlines()[-1] == "springmass run: stopped; the outputs hold the rows up to t = 0 s", out.stderr
    _, few = read_csv(tmp_path / "few.csv")
    assert few.shape[0] == 1 and few[0, 0] == 0.0


def test_analysis_errors_name_particles_and_springs_as_the_file_does(tmp_path):
    # The library names elements by index; the tool adds the names the file gives them.
    free = {"springmass": 1, "name": "free", "gravity": [0, 0, -9.81],
            "particles": [{"name": "a", "position": [0, 0, 0]}, {"name": "b", "position": [1, 0, 0]},
                          {"position": [2, 0, 0]}],
            "springs": [{"a": "a", "b": "b", "stiffness": 10}, {"a": "b", "b": 2, "stiffness": 10}]}
    (tmp_path / "free.json").write_text(json.dumps(free))
    err = cli("statics", tmp_path / "free.json", status=1).stderr
    assert "particle 0 (a) and the 2 other particle(s)" in err and "fix one of them" in err, err
    # The tool's message names its command and the file once; the library's own "statics: " that
    # began the reason is not repeated after them.
    assert err.startswith(f"springmass statics: {tmp_path / 'free.json'}: no static equilibrium: "), err
    coincident = {"springmass": 1, "name": "coincident", "gravity": [0, 0, 0],
                  "particles": [{"name": "a", "position": [0, 0, 0], "fixed": True},
                                {"name": "b", "position": [0, 0, 0]}, {"position": [1, 0, 0]}],
                  "springs": [{"a": 2, "b": "b", "stiffness": 10},
                              {"a": "a", "b": "b", "stiffness": 10, "rest_length": 1}]}
    (tmp_path / "coincident.json").write_text(json.dumps(coincident))
    err = cli("modes", tmp_path / "coincident.json", status=1).stderr
    # An unnamed particle keeps its index; "particles 0 and 1" names both.
    assert "spring 1 (between a and b) (rest length 1 m) has its particles 0 (a) and 1 (b) at one point" in err, err
    assert err.startswith(f"springmass modes: {tmp_path / 'coincident.json'}: spring 1 "), err
    bad = dict(coincident, springs=coincident["springs"][::-1])
    (tmp_path / "bad.json").write_text(json.dumps(bad))
    err = cli("modes", tmp_path / "bad.json", status=1).stderr
    assert "spring 0 (between a and b)" in err, err
    chain = dict(bad, springs=[{"a": "b", "b": 2, "stiffness": 10, "rest_length": 1}], particles=[
        {"name": "a", "position": [0, 0, 0], "fixed": True}, {"name": "b", "position": [0, 0, 0]},
        {"position": [0, 0, 0]}])
    (tmp_path / "chain.json").write_text(json.dumps(chain))
    err = cli("modes", tmp_path / "chain.json", status=1).stderr
    assert "spring 0 (between b and particle 2)" in err and "particles 1 (b) and 2 at one point" in err, err


def vtp_sections(path):
    """The same as vtk_sections, of a VTK XML polydata file (.vtp) as ParaView's readers take it:
    ASCII data arrays whose sizes the piece's counts give, lines by connectivity and offsets."""
    root = ET.parse(path).getroot()
    assert root.tag == "VTKFile" and root.get("type") == "PolyData", root.attrib
    pieces = root.findall("./PolyData/Piece")
    assert len(pieces) == 1
    piece = pieces[0]
    n, count = int(piece.get("NumberOfPoints")), int(piece.get("NumberOfLines"))

    def values(array, size):
        assert array.get("format") == "ascii", array.attrib
        data = np.array([float(v) for v in (array.text or "").split()])
        assert data.size == size * int(array.get("NumberOfComponents", "1")), (array.attrib, data.size)
        return data.reshape(size, -1) if array.get("NumberOfComponents") else data

    points = values(piece.find("./Points/DataArray"), n)
    lines = []
    if count > 0:
        connectivity = values(piece.find("./Lines/DataArray[@Name='connectivity']"), 2 * count).astype(int)
        offsets = values(piece.find("./Lines/DataArray[@Name='offsets']"), count).astype(int)
        assert list(offsets) == [2 * (k + 1) for k in range(count)]
        lines = [(int(connectivity[2 * k]), int(connectivity[2 * k + 1])) for k in range(count)]
    else:
        assert piece.find("./Lines") is None or not piece.find("./Lines").findall("DataArray")
    vectors = {a.get("Name"): values(a, n) for a in piece.findall("./PointData/DataArray")}
    scalars = {a.get("Name"): values(a, count) for a in piece.findall("./CellData/DataArray")}
    return points, lines, vectors, scalars


def test_a_series_file_that_cannot_be_written_is_reported_on_a_line_of_its_own(tmp_path):
    # On a terminal the progress line rewrites itself without a line feed; the error of a series
    # file that cannot be written (a folder in the place of the 1001st) starts a line of its own.
    # The run is held for over a second by its CSV's reader, which lets the pipe fill (1000 rows
    # of the oscillator are some 200 KB, a pipe holds 64 KB), so that the line is shown first. The
    # second is counted from the first rows read, which the tool writes after its progress clock
    # started (its header is 163 bytes, its first 4 KB of output come from rows): counted from the
    # start of the process, a start 0.6 s late, as on a busy machine, left the run under a second
    # when it reached the 1001st file, and the line unshown.
    vtk = tmp_path / "series"
    (vtk / "oscillator_001000.vtp").mkdir(parents=True)
    master, terminal = os.openpty()
    run = subprocess.Popen([str(CLI), "run", str(MODELS / "oscillator.json"), "--t-end", "2", "--output-interval",
                            "0.001", "-o", "-", "--vtk", str(vtk)], stdout=subprocess.PIPE, stderr=terminal)
    os.close(terminal)
    try:
        run.stdout.read(1)
        time.sleep(1.5)
        run.stdout.read()
        assert run.wait(timeout=60) == 1
    finally:
        run.stdout.close()
    shown = b""
    while True:
        try:
            chunk = os.read(master, 4096)
        except OSError:  # the terminal's other end is closed and everything read
            break
        if not chunk:
            break
        shown += chunk
    os.close(master)
    shown = shown.decode()
    assert "\rspringmass run: t = " in shown, shown
    assert re.search(rf"(^|\n)springmass run: cannot write {re.escape(str(vtk))}/oscillator_001000\.vtp: "
                     r"Is a directory\r?\n", shown), shown


def test_a_series_index_that_cannot_be_written_stops_the_run_at_its_row(tmp_path):
    # A full disk, here a limit on the size of a file (which fails the same way) of 2 KB: each of
    # the oscillator's frames (some 1000 bytes) fits, its index (a line of some 60 bytes a row)
    # outgrows it after some 30 of the 501 rows. The run stops at the row whose index entry fails,
    # naming the index, and the index on disk names every frame written before that row: it was
    # written through at every row, not kept in a buffer that a failure (a full disk: no room for
    # the buffer at the end) or a kill loses.
    vtk = tmp_path / "series"
    limit = 2048  # [bytes]

    def limited():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails (EFBIG)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    out = subprocess.run([str(CLI), "run", str(MODELS / "oscillator.json"), "-q", "-o", "-", "--vtk", str(vtk)],
                         capture_output=True, text=True, preexec_fn=limited, timeout=60)
    assert out.returncode == 1 and out.stderr == f"springmass run: cannot write {vtk}/oscillator.pvd: File too large\n", (
        out.returncode, out.stderr)
    frames = sorted(p.name for p in vtk.glob("oscillator_*.vtp"))
    rows = out.stdout.splitlines()[1:]
    assert 10 < len(frames) < 50 and len(rows) == len(frames), (len(frames), len(rows))
    entries = re.findall(r'<DataSet timestep="[^"]*" file="([^"]*)"/>\n', (vtk / "oscillator.pvd").read_text())
    assert entries == frames[:-1]


@pytest.mark.parametrize("name", ["HUP", "INT", "TERM"])
def test_run_goes_on_through_a_signal_it_was_started_with_ignored(name):
    # nohup starts a command with SIGHUP ignored, a shell script its background jobs with SIGINT
    # ignored: the one who started the run asked that such a signal leave it running, so the run
    # goes on to its last row and succeeds. The signal is sent while the run is writing: its
    # first rows have been read (the 163-byte header alone fills no buffer, so they come from the
    # loop over the rows, after the tool has set up its signals) and the rest, some 200 KB, cannot
    # fit in the pipe (64 KB) until it is read.
    sig = signal.Signals["SIG" + name]
    run = subprocess.Popen([str(CLI), "run", str(MODELS / "oscillator.json"), "-q", "--t-end", "2", "--output-interval",
                            "0.001", "-o", "-"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           preexec_fn=lambda: signal.signal(sig, signal.SIG_IGN))
    try:
        first = run.stdout.read(1)
        run.send_signal(sig)
        rows = (first + run.stdout.read()).decode().splitlines()
        err = run.stderr.read()  # -q: nothing on stderr unless the run fails
        assert run.wait(timeout=60) == 0 and err == b"", (run.returncode, err)
    finally:
        run.stdout.close()
        run.stderr.close()
    assert len(rows) == 2002 and rows[-1].split(",")[0] == "2", rows[-1]


def test_run_into_a_pipe_without_a_reader_with_sigpipe_ignored_fails_to_write():
    # SIGPIPE ignored, as by a program that starts the tool to handle a reader that goes away
    # itself: a write to the pipe fails (EPIPE), which is an output that cannot be written (exit
    # status 1, named with the reason), as for statics, modes and check, not a death by SIGPIPE.
    read_end, write_end = os.pipe()
    os.close(read_end)
    try:
        out = subprocess.run([str(CLI), "run", str(MODELS / "oscillator.json"), "-q", "-o", "-"], stdout=write_end,
                             stderr=subprocess.PIPE, text=True, timeout=60, restore_signals=False,
                             preexec_fn=lambda: signal.signal(signal.SIGPIPE, signal.SIG_IGN))
    finally:
        os.close(write_end)
    assert out.returncode == 1 and out.stderr == "springmass run: cannot write standard output: Broken pipe\n", (
        out.returncode, out.stderr)


def test_run_stopped_within_a_long_advance_ends_there(tmp_path):
    # Between two rows the run steps as in one advance, checking for a stop after every internal
    # step: a run stopped there ends at once with the rows written before, not after the advance
    # (here the only one, to t = 0.5 s, some 10 s of work on a stiff hanging sheet). The signal
    # is sent while row 0 is written: the header and the first bytes of row 0, whose 1728
    # positions do not fit the 4 kB buffer of a pipe, have been read.
    model = tmp_path / "slow.json"
    model.write_text(json.dumps({
        "springmass": 1, "name": "slow", "gravity": [0, 0, -9.81],
        "structures": [{"type": "sheet", "name": "s", "edge_u": [1, 0, 0], "edge_v": [0, 1, 0], "nu": 24, "nv": 24,
                        "mass": 1, "structural": {"strain_stiffness": 1000}, "shear": {"strain_stiffness": 1000}}],
        "fixed": ["s[0,0]", "s[0,23]"]}))
    run = subprocess.Popen([str(CLI), "run", str(model), "-q", "--t-end", "0.5", "--output-interval", "0.5",
                            "--positions", "-o", "-"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        text = b""
        while b"\n" not in text[:-1]:
            chunk = run.stdout.read1(65536)
            assert chunk, text[-80:]
            text += chunk
        run.send_signal(signal.SIGTERM)
        text += run.stdout.read()
        err = run.stderr.read().decode()
        assert run.wait(timeout=60) == -signal.SIGTERM, err
    finally:
        run.stdout.close()
        run.stderr.close()
    rows = text.decode().splitlines()
    assert len(rows) == 2 and rows[1].split(",")[0] == "0", [r[:20] for r in rows]
    # Row 0 is whole, its last bytes too, which were still in the output's buffer at the stop.
    header, row = csv.reader(rows)
    assert text.endswith(b"\n") and len(row) == len(header), text[-80:]
    assert err == "springmass run: stopped by Terminated; the outputs hold the rows up to t = 0 s\n", err


def test_vtk_series_matches_the_csv_and_drops_broken_springs(tmp_path):
    model = MODELS / "tearing_cloth.json"
    vtk = tmp_path / "vtk"
    path = tmp_path / "tear.csv"
    stats = cli("run", model, "-o", path, "--positions", "--output-interval", 0.1, "--vtk", vtk).stderr
    header, rows = read_csv(path)
    # Each break names the spring's particles as the file does: neighbours on the cloth's grid.
    breaks = re.findall(r"spring (\d+) \(between cloth\[(\d+),(\d+)\] and cloth\[(\d+),(\d+)\]\) broke at", stats)
    assert len(breaks) > 0 and len(breaks) == stats.count(" broke at")
    for _, i, j, k, l in breaks:
        assert 0 < max(abs(int(i) - int(k)), abs(int(j) - int(l))) <= 2
    broken = [int(b[0]) for b in breaks]
    # The index lists one file per row, at the row's time.
    index = ET.parse(vtk / "tearing_cloth.pvd").getroot()
    sets = index.findall("./Collection/DataSet")
    assert [float(d.get("timestep")) for d in sets] == list(rows[:, 0])
    assert [d.get("file") for d in sets] == [f"tearing_cloth_{k:06d}.vtp" for k in range(len(rows))]
    assert sorted(p.name for p in vtk.glob("*.vtp")) == [d.get("file") for d in sets]
    first = next(i for i, name in enumerate(header) if name.startswith("particle."))
    springs = int(re.search(r"springs\s+(\d+)", cli("check", model).stdout).group(1))
    for k, d in enumerate(sets):
        points, lines, _, _ = vtp_sections(vtk / d.get("file"))
        # Points are written exactly, as the CSV's positions are.
        assert np.array_equal(points.ravel(), rows[k, first:])
        assert len(set(lines)) == len(lines)
        if k == 0:
            all_lines = lines
            assert len(lines) == springs
        # Each file's lengths and strains imply the same rest lengths l0 = L / (1 + strain): 9
        # significant digits each.
        _, _, _, scalars = vtp_sections(vtk / d.get("file"))
        lengths = np.linalg.norm(points[[b for _, b in lines]] - points[[a for a, _ in lines]], axis=1)
        implied = dict(zip(lines, lengths / (1.0 + scalars["strain"])))
        if k == 0:
            rest = implied
        assert all(implied[line] == pytest.approx(rest[line], rel=1e-7) for line in lines)
    # The last file has the intact springs only: every spring that broke is gone, the rest stay.
    _, last_lines, _, _ = vtp_sections(vtk / sets[-1].get("file"))
    assert len(last_lines) == springs - len(broken)
    assert [all_lines[s] for s in sorted(set(range(springs)) - set(broken))] == last_lines


def test_the_series_index_names_vtk_xml_polydata_files(tmp_path):
    # ParaView reads a .pvd index with its XML collection reader, which picks each file's reader by
    # its extension among the XML formats (.vtp, .vtu, ...) and has none for a legacy .vtk file: an
    # index of legacy files opens to "Could not determine the data type for the first dataset".
    # So every file the index names is VTK XML polydata, with its time as the field TimeValue.
    vtk = tmp_path / "vtk"
    cli("run", MODELS / "two_mass_chain.json", "-q", "-o", tmp_path / "chain.csv", "--t-end", 0.05,
        "--vtk", vtk)
    index = ET.parse(vtk / "two_mass_chain.pvd").getroot()
    assert index.tag == "VTKFile" and index.get("type") == "Collection"
    sets = index.findall("./Collection/DataSet")
    assert len(sets) == 6
    for d in sets:
        assert d.get("file").endswith(".vtp"), d.get("file")
        root = ET.parse(vtk / d.get("file")).getroot()
        assert root.get("type") == "PolyData" and root.get("byte_order") == "LittleEndian"
        time = root.find("./PolyData/FieldData/DataArray[@Name='TimeValue']")
        assert float(time.text) == float(d.get("timestep"))
        points, lines, vectors, scalars = vtp_sections(vtk / d.get("file"))
        assert points.shape == (3, 3) and lines == [(0, 1), (1, 2)]
        assert set(vectors) == {"velocity"} and set(scalars) == {"tension", "strain", "spring"}
        assert list(scalars["spring"]) == [0, 1]


def test_vtk_files_carry_velocities_tensions_and_strains(tmp_path):
    # The bundled oscillator (a 1 kg bob on a 40 N/m spring of rest length 0.5 m with 0.4 N s/m
    # damping, from a fixed anchor at the origin): each VTK file's velocity vectors are the CSV's,
    # and its spring's tension and strain follow from the points and velocities by the laws,
    # ks (L - l0) + kd u . (v_b - v_a) and (L - l0) / l0. The files hold the points exactly and the
    # rest to 9 significant digits: the velocities to 5e-9 relative, the strain (under 0.4) to 2e-10
    # (3e-9 allowed) and the tension (under 8 N, with 40 N/m times the strain's rounding) to 1e-8 N
    # (1e-7 N allowed).
    vtk = tmp_path / "vtk"
    header, rows = run_csv(tmp_path, MODELS / "oscillator.json", "--output-interval", 0.25, "--vtk", vtk)
    vx = header.index("tip.vx")
    for k, row in enumerate(rows):
        points, lines, vectors, scalars = vtp_sections(vtk / f"oscillator_{k:06d}.vtp")
        assert lines == [(0, 1)] and set(scalars) == {"tension", "strain", "spring"}
        np.testing.assert_allclose(vectors["velocity"][1], row[vx:vx + 3], rtol=1e-8, atol=1e-12)
        d = points[1] - points[0]
        length = np.linalg.norm(d)
        rate = d @ vectors["velocity"][1] / length
        assert scalars["strain"][0] == pytest.approx((length - 0.5) / 0.5, rel=1e-8, abs=3e-9)
        assert scalars["tension"][0] == pytest.approx(40 * (length - 0.5) + 0.4 * rate, rel=1e-8, abs=1e-7)
    # A zero-length spring has no strain: its file carries tensions alone.
    pair = {"springmass": 1, "name": "pair", "gravity": [0, 0, -9.81],
            "particles": [{"name": "anchor", "position": [0, 0, 0], "fixed": True},
                          {"name": "bob", "position": [0, 0, -1], "mass": 1}],
            "springs": [{"a": "anchor", "b": "bob", "stiffness": 10, "rest_length": 0}]}
    path = tmp_path / "pair.json"
    path.write_text(json.dumps(pair))
    cli("run", path, "-q", "--t-end", 0.1, "--output-interval", 0.1, "-o", tmp_path / "pair.csv", "--vtk", vtk)
    points, _, _, scalars = vtp_sections(vtk / "pair_000000.vtp")
    assert set(scalars) == {"tension", "spring"} and scalars["tension"][0] == pytest.approx(10.0)


def test_vtk_points_are_the_csv_positions_exactly_far_from_the_origin(tmp_path):
    # The geometry of a VTK file is the differences of its points. A 1 m rope of 1 cm segments
    # 100 km out along x, hanging from its first particle: at 9 significant digits its points
    # would be rounded to 0.5 mm, half a segment, and the strains that follow from them would be
    # wrong by up to 0.1 (the rope's own strains stay below 1e-3). Its points (in the run's series
    # and in statics' legacy file) are the CSV's positions to the last bit, and the strains they
    # imply are the file's strain array: 9 significant digits of strains below 1e-3, plus lengths
    # of 1 cm from coordinates of 1e5 m (1.5e-11 m of rounding, 1.5e-9 of strain); 1e-8 allowed.
    far = {"springmass": 1, "name": "far_rope",
           "structures": [{"type": "rope", "name": "rope", "start": [100000, 0, 0], "end": [100001, 0, 0],
                           "segments": 100, "mass": 0.1, "structural": {"strain_stiffness": 1000}}],
           "fixed": ["rope[0]"]}
    model = tmp_path / "far_rope.json"
    model.write_text(json.dumps(far))
    vtk = tmp_path / "vtk"
    header, rows = run_csv(tmp_path, model, "--positions", "--t-end", 0.2, "--output-interval", 0.1, "--vtk", vtk)
    first = next(i for i, name in enumerate(header) if name.startswith("particle."))
    for k, row in enumerate(rows):
        points, lines, _, scalars = vtp_sections(vtk / f"far_rope_{k:06d}.vtp")
        assert np.array_equal(points.ravel(), row[first:])
        assert lines == [(j, j + 1) for j in range(100)]
        lengths = np.linalg.norm(np.diff(points, axis=0), axis=1)
        assert np.abs(scalars["strain"]).max() < 1e-3
        np.testing.assert_allclose((lengths - 0.01) / 0.01, scalars["strain"], rtol=0, atol=1e-8)
    out = tmp_path / "statics.csv"
    cli("statics", model, "-q", "-o", out, "--vtk", tmp_path / "statics")
    header, rest = read_csv(out)
    points, _, _, _ = vtk_sections(tmp_path / "statics" / "statics.vtk")
    assert np.array_equal(points, rest[:, header.index("x"):header.index("x") + 3])


def test_breaks_close_together_are_logged_at_their_own_times(tmp_path):
    # A bob drifts at 1 m/s from a fixed anchor, no force on it (two springs of stiffness 0, rest
    # length 1 m): its distance is 1 + t, and the springs, of break strains 0.5 and 0.5 + 2e-10,
    # break at t = 0.5 s and 2e-10 s later, in two events. CVODE follows the straight line
    # exactly and locates each crossing to its time resolution, 100 eps (|t| + |h|), about 1e-13 s
    # here: the log gives each break's time to 1e-13 s, so the two differ by 2e-10 s to 2e-13 s.
    drift = {"springmass": 1, "name": "drift", "gravity": [0, 0, 0],
             "particles": [{"name": "anchor", "position": [0, 0, 0], "fixed": True},
                           {"name": "bob", "position": [1, 0, 0], "velocity": [1, 0, 0], "mass": 1}],
             "springs": [{"a": "anchor", "b": "bob", "stiffness": 0, "rest_length": 1, "break_strain": 0.5},
                         {"a": "anchor", "b": "bob", "stiffness": 0, "rest_length": 1,
                          "break_strain": 0.5000000002}]}
    path = tmp_path / "drift.json"
    path.write_text(json.dumps(drift))
    stats = cli("run", path, "--t-end", 1, "-o", "-").stderr
    logged = re.findall(r"^  spring (\d) \(between anchor and bob\) broke at t = (\S+) s$", stats, re.M)
    assert [int(s) for s, _ in logged] == [0, 1], stats
    first, second = (float(t) for _, t in logged)
    assert first == pytest.approx(0.5, abs=1e-13) and second == pytest.approx(0.5000000002, abs=1e-13), stats
    assert second - first == pytest.approx(2e-10, abs=2e-13), stats


def test_each_line_of_a_series_gives_its_spring_number_after_a_break(tmp_path):
    # Three bobs drift away from a fixed anchor at 1 m/s along x, y and z, from 1 m, each on a
    # spring of stiffness 0 (no force: their distances are 1 + t) and rest length 1 m; the middle
    # spring, 1, breaks at strain 0.5, at t = 0.5 s. Its line is left out of the frames after that:
    # the second line is then spring 2's, which the message calls "spring 2", and the cell array
    # `spring` says so, where the line's place alone would say spring 1.
    drift = {"springmass": 1, "name": "drift3", "gravity": [0, 0, 0],
             "particles": [{"name": "anchor", "position": [0, 0, 0], "fixed": True},
                           {"name": "b0", "position": [1, 0, 0], "velocity": [1, 0, 0]},
                           {"name": "b1", "position": [0, 1, 0], "velocity": [0, 1, 0]},
                           {"name": "b2", "position": [0, 0, 1], "velocity": [0, 0, 1]}],
             "springs": [{"a": "anchor", "b": "b0", "stiffness": 0},
                         {"a": "anchor", "b": "b1", "stiffness": 0, "break_strain": 0.5},
                         {"a": "anchor", "b": "b2", "stiffness": 0}]}
    path = tmp_path / "drift3.json"
    path.write_text(json.dumps(drift))
    vtk = tmp_path / "vtk"
    stats = cli("run", path, "--t-end", 1, "--output-interval", 0.25, "-o", tmp_path / "drift3.csv",
                "--vtk", vtk).stderr
    logged = re.findall(r"^  spring (\d) \(between anchor and (\w+)\) broke at t = (\S+) s$", stats, re.M)
    assert len(logged) == 1 and logged[0][:2] == ("1", "b1") and float(logged[0][2]) == pytest.approx(0.5), stats
    for k in range(5):
        _, lines, _, scalars = vtp_sections(vtk / f"drift3_{k:06d}.vtp")
        # Rows at 0, 0.25 s hold every spring; the row at 0.5 s is taken just after the break (the
        # break is found within 1e-13 s of 0.5 s, before or after: checked by the line's absence
        # from 0.75 s on only).
        if k < 2:
            assert lines == [(0, 1), (0, 2), (0, 3)] and list(scalars["spring"]) == [0, 1, 2]
        elif k > 2:
            assert lines == [(0, 1), (0, 3)] and list(scalars["spring"]) == [0, 2]
        assert len(scalars["spring"]) == len(lines)


def test_a_spring_that_breaks_is_logged_at_its_time_and_leaves_no_lines(tmp_path):
    # A 1 kg bob hangs from a fixed anchor on a 10 N/m spring at its rest length, 1 m, and is let
    # go: z(t) = -1 - (g / omega^2) (1 - cos(omega t)) with omega^2 = k / m, until the spring's
    # strain reaches its break strain 0.01 at t_b = acos(1 - 0.01 omega^2 l0 / g) / omega. From then
    # on no spring is intact: the VTK files have no LINES section, which VTK's legacy reader would
    # refuse as "LINES 0 0".
    snap = {"springmass": 1, "name": "snap", "gravity": [0, 0, -9.81],
            "particles": [{"name": "anchor", "position": [0, 0, 0], "fixed": True},
                          {"name": "bob", "position": [0, 0, -1], "mass": 1}],
            "springs": [{"a": "anchor", "b": "bob", "stiffness": 10, "rest_length": 1, "break_strain": 0.01}]}
    path = tmp_path / "snap.json"
    path.write_text(json.dumps(snap))
    vtk = tmp_path / "vtk"
    stats = cli("run", path, "--t-end", 0.2, "--output-interval", 0.1, "-o", tmp_path / "snap.csv",
                "--vtk", vtk).stderr
    assert re.search(r"^springmass run: snap to t = 0\.2 s with .*, 1 spring broke; wall ", stats, re.M), stats
    logged = re.findall(r"^  spring 0 \(between anchor and bob\) broke at t = (\S+) s$", stats, re.M)
    omega = math.sqrt(10 / 1)
    t_break = math.acos(1 - 0.01 * omega ** 2 * 1 / 9.81) / omega
    # The default tolerances (rtol 1e-6, atol 1e-8 m) place the bob to about 1e-6 m; it falls at
    # g t = 0.44 m/s there, so the crossing is found to about 2.3e-6 s (measured 8e-7 s).
    assert len(logged) == 1 and float(logged[0]) == pytest.approx(t_break, abs=5e-6), stats
    assert vtp_sections(vtk / "snap_000000.vtp")[1] == [(0, 1)]
    for k in (1, 2):
        points, lines, _, _ = vtp_sections(vtk / f"snap_{k:06d}.vtp")
        assert points.shape == (2, 3) and lines == []
        assert "<Lines>" not in (vtk / f"snap_{k:06d}.vtp").read_text()


def shortest_text(value):
    """A number as README.md says the tool writes it: the fewest of 15, 16 or 17 significant digits
    that read back to exactly the same double."""
    for digits in (15, 16):
        text = f"{value:.{digits}g}"
        if float(text) == value:
            return text
    return f"{value:.17g}"


# tests/python/models/driven_oscillator.json: a bob (force port "tip", 2 kg) on a spring (50 N/m,
# rest length 0.5 m) from an anchor (motion port "base", fixed in the file) at the origin,
# released at x = 0.7 m; no gravity, no damping.
OSC = ROOT / "tests" / "python" / "models" / "driven_oscillator.json"
OSC_M, OSC_K, OSC_L0, OSC_X0 = 2.0, 50.0, 0.5, 0.7
TIGHT_RUN = ("--rtol", "1e-10", "--atol", "1e-12", "--t-end", "2", "--output-interval", "0.1")


def test_run_takes_input_signals_as_closed_forms(tmp_path):
    # A force growing as r t (rows at 0 and 2 s): M u'' + K u = r t from u(0) = x0 - l0 at rest,
    # u = (x0 - l0) cos(w t) + r / K (t - sin(w t) / w). The anchor's velocity growing as a t (its
    # position, not given, the integral from the origin): in its frame M u'' = -K u - M a,
    # u = -M a / K + (x0 - l0 + M a / K) cos(w t), and the anchor feels K u. At rtol 1e-10 the
    # error of the state over 2 s is near 1e-8 m (measured 2.5e-9 and 1.9e-9 m): 1e-6 m, K times that
    # for the force.
    w = math.sqrt(OSC_K / OSC_M)
    (tmp_path / "ramp.csv").write_text("time,tip.fx\n0,0\n2,6\n")
    header, rows = run_csv(tmp_path, OSC, "--input", tmp_path / "ramp.csv", *TIGHT_RUN)
    t, x = rows[:, 0], rows[:, header.index("tip.x")]
    u = (OSC_X0 - OSC_L0) * np.cos(w * t) + 3.0 / OSC_K * (t - np.sin(w * t) / w)
    assert len(t) == 21 and np.max(np.abs(x - (OSC_L0 + u))) < 1e-6
    # The same signals from standard input (--input -) give the same file, bit for bit.
    subprocess.run([str(CLI), "run", str(OSC), "-q", "-o", str(tmp_path / "piped.csv"), "--input", "-", *TIGHT_RUN],
                   input="time,tip.fx\n0,0\n2,6\n", text=True, check=True, timeout=60)
    assert (tmp_path / "piped.csv").read_bytes() == (tmp_path / "run.csv").read_bytes()
    # Rows that straddle the start, -6 N at -2 s and 6 N at 2 s, give the same 3 t over [0, 2] s:
    # linear between rows (--help), not the first row's value held from t = 0 (3 t - 6).
    (tmp_path / "straddle.csv").write_text("time,tip.fx\n-2,-6\n2,6\n")
    _, straddled = run_csv(tmp_path, OSC, "--input", tmp_path / "straddle.csv", *TIGHT_RUN)
    assert np.max(np.abs(straddled[:, header.index("tip.x")] - (OSC_L0 + u))) < 1e-6
    (tmp_path / "accelerate.csv").write_text("time,base.vx\n0,0\n2,1.6\n")
    header, rows = run_csv(tmp_path, OSC, "--input", tmp_path / "accelerate.csv", *TIGHT_RUN)
    t, x, f = rows[:, 0], rows[:, header.index("tip.x")], rows[:, header.index("base.fx")]
    a = 0.8
    u = -OSC_M * a / OSC_K + (OSC_X0 - OSC_L0 + OSC_M * a / OSC_K) * np.cos(w * t)
    assert np.max(np.abs(x - (0.5 * a * t * t + OSC_L0 + u))) < 1e-6
    assert np.max(np.abs(f - OSC_K * u)) < OSC_K * 1e-6


def test_run_takes_rows_that_keep_the_inputs_course_as_no_change(tmp_path):
    # A force 3 t up to 1 s, then held at 3 N: by superposition the ramp's response of
    # test_run_takes_input_signals_as_closed_forms less that of a ramp starting at 1 s. Given by
    # three rows or sampled every 1/64 s (binary fractions: every slope exactly 3 or 0), it is the
    # same signal, and the rows within its straight stretches change nothing: the same file to the
    # bit (each row used to end a step, the results then different within the tolerances). The
    # row at 1 s, where the slope changes, is still where the run takes the new course: carried on
    # at 3 N/s the force would leave the bob 3 / K (t - 1) off, up to 0.06 m at 2 s. Tolerance as in
    # that test.
    w, r = math.sqrt(OSC_K / OSC_M), 3.0
    (tmp_path / "coarse.csv").write_text("time,tip.fx\n0,0\n1,3\n2,3\n")
    fine = [f"{k / 64!r},{min(3 * k / 64, 3.0)!r}" for k in range(129)]
    (tmp_path / "fine.csv").write_text("time,tip.fx\n" + "\n".join(fine) + "\n")
    header, rows = run_csv(tmp_path, OSC, "--input", tmp_path / "coarse.csv", *TIGHT_RUN, name="coarse_run.csv")
    run_csv(tmp_path, OSC, "--input", tmp_path / "fine.csv", *TIGHT_RUN, name="fine_run.csv")
    assert (tmp_path / "fine_run.csv").read_bytes() == (tmp_path / "coarse_run.csv").read_bytes()
    t, x = rows[:, 0], rows[:, header.index("tip.x")]
    s = np.maximum(t - 1.0, 0.0)
    u = (OSC_X0 - OSC_L0) * np.cos(w * t) + r / OSC_K * (t - np.sin(w * t) / w - (s - np.sin(w * s) / w))
    assert len(t) == 21 and np.max(np.abs(x - (OSC_L0 + u))) < 1e-6
    # The anchor given a constant position and a constant velocity, 0 m and 1 m/s: every row sets it
    # back to 0 m (--help: "with the velocities given ... from the positions given"), so the rows
    # count though no signal's slope changes. Rows every 0.25 s, outputs every 0.1 s: at 0.5 s
    # (a row) the anchor is back at 0; at 0.7 s it has moved 0.2 m from there.
    (tmp_path / "both.csv").write_text("time,base.x,base.vx\n" + "".join(f"{k / 4},0,1\n" for k in range(9)))
    header, rows = run_csv(tmp_path, OSC, "--input", tmp_path / "both.csv", "--positions", *TIGHT_RUN)
    anchor = dict(zip(np.round(rows[:, 0], 9), rows[:, header.index("particle.anchor.x")]))
    assert anchor[0.5] == 0.0 and anchor[0.7] == pytest.approx(0.2, abs=1e-12)


@pytest.mark.parametrize("input_changes", ["restart", "keep"])
def test_run_restarts_where_a_held_input_jumps_by_much_unless_told_to_keep_the_history(tmp_path, input_changes):
    # Held inputs on the undamped bob over 10 s, against its exact response. 0.1 sin(t) N held over
    # each 1 ms jumps at every row by at most 1e-4 N: 5e-8 m/s over a stretch, within the velocity
    # tolerance (1e-6 m/s), so CVODE's history carries the jumps either way: 1.8e-6 m off (measured;
    # a restart at each, as every jump had before, left it 6.0e-3 m off the 0.2 m swing). A square
    # wave of +-1 N switched every 0.25 s jumps by 2 N: restarted at each jump by default, 1.1e-4 m
    # off; with --input-changes keep, 2.0e-4 m (measured: 1e-3 m, from a stretch's first steps
    # taken with a history that assumed the force before). The summary counts the restarts.
    def run(name, forces, h):
        rows = [f"{k * h!r},{f!r}\n{(k + 1) * h!r},{f!r}" for k, f in enumerate(forces)]
        (tmp_path / f"{name}.csv").write_text("time,tip.fx\n" + "\n".join(rows) + "\n")
        out = tmp_path / f"{name}_run.csv"
        err = cli("run", OSC, "--input", tmp_path / f"{name}.csv", "--input-changes", input_changes, "--t-end",
                  "10", "--output-interval", "10", "-o", out).stderr
        header, result = read_csv(out)
        off = abs(result[-1, header.index("tip.x")] - undamped_response_to_held_forces(forces, h)[0])
        return off, int(re.search(r"(\d+) restarts", err).group(1))

    off, restarts = run("sine", [0.1 * math.sin(k * 1e-3) for k in range(10000)], 1e-3)
    assert off < 2e-5 and restarts == 0
    off, restarts = run("square", [(-1.0) ** k for k in range(40)], 0.25)
    assert off < 1e-3 and restarts == (40 if input_changes == "restart" else 0)


def test_run_shows_the_state_after_a_jump_at_its_output_row(tmp_path):
    # The anchor jumps from 0 to 0.1 m at t = 0.5 s, an output time: that row's base.fx is the
    # spring's K (tip.x - 0.1 - l0), after the jump, as --help says (fmpy records the one before: README).
    (tmp_path / "jump.csv").write_text("time,base.x\n0,0\n0.5,0\n0.5,0.1\n")
    header, rows = run_csv(tmp_path, OSC, "--input", tmp_path / "jump.csv", "--t-end", "1", "--output-interval", "0.5")
    x, f = rows[:, header.index("tip.x")], rows[:, header.index("base.fx")]
    assert list(rows[:, 0]) == [0, 0.5, 1]
    assert abs(f[0] - OSC_K * (x[0] - OSC_L0)) < 1e-12
    assert abs(f[1] - OSC_K * (x[1] - 0.1 - OSC_L0)) < 1e-12 and abs(f[2] - OSC_K * (x[2] - 0.1 - OSC_L0)) < 1e-12


def test_run_holds_input_signals_before_the_first_row_and_after_the_last(tmp_path):
    # Rows at 0.5 s and 1 s only, both 3 N: held before the first and after the last (--help), the
    # force is 3 N over the whole run, M u'' + K u = F from u(0) = x0 - l0 at rest,
    # u = F / K + (x0 - l0 - F / K) cos(w t); no force before 0.5 s (u = (x0 - l0) cos(w t) there)
    # would leave the bob F / K (1 - cos(w t)), up to 0.12 m, off that. The anchor held at 0.1 m
    # from the start the same way: the anchor's force, K (tip.x - 0.1 - l0), at every row.
    # Tolerances as in test_run_takes_input_signals_as_closed_forms.
    w = math.sqrt(OSC_K / OSC_M)
    (tmp_path / "held.csv").write_text("time,tip.fx,base.x\n0.5,3,0.1\n1,3,0.1\n")
    header, rows = run_csv(tmp_path, OSC, "--input", tmp_path / "held.csv", *TIGHT_RUN)
    t, x = rows[:, 0], rows[:, header.index("tip.x")]
    u = 3.0 / OSC_K + (OSC_X0 - 0.1 - OSC_L0 - 3.0 / OSC_K) * np.cos(w * t)
    assert len(t) == 21 and np.max(np.abs(x - (0.1 + OSC_L0 + u))) < 1e-6
    # The anchor's force is K (L - l0) of the row's own state, as in the jump test above: round-off
    # only (measured 4e-16 N).
    f = rows[:, header.index("base.fx")]
    assert np.max(np.abs(f - OSC_K * (x - 0.1 - OSC_L0))) < 1e-12


def test_run_leaves_a_motion_port_the_input_file_does_not_name_free(tmp_path):
    # The anchor made free (2 kg) and only the force port named (0 N): the motion port's particle
    # moves as the file says (--help), not driven. Two equal masses M on the spring, released at rest
    # with it stretched by s0 = x0 - l0: the centre stays at x0 / 2 and the stretch oscillates at
    # w = sqrt(K / mu), mu = M / 2, so the anchor is at x0 / 2 - (l0 + s0 cos(w t)) / 2. Driven where
    # the file starts it, it would stay at 0. Tolerance as in test_run_takes_input_signals_as_closed_forms.
    model = json.loads(OSC.read_text())
    model["particles"][0] = {"name": "anchor", "position": [0, 0, 0], "mass": OSC_M}
    path = tmp_path / "free_anchor.json"
    path.write_text(json.dumps(model))
    (tmp_path / "none.csv").write_text("time,tip.fx\n0,0\n")
    header, rows = run_csv(tmp_path, path, "--input", tmp_path / "none.csv", "--positions", *TIGHT_RUN)
    t, anchor = rows[:, 0], rows[:, header.index("particle.anchor.x")]
    w = math.sqrt(OSC_K / (OSC_M / 2))
    expected = OSC_X0 / 2 - (OSC_L0 + (OSC_X0 - OSC_L0) * np.cos(w * t)) / 2
    assert len(t) == 21 and np.max(np.abs(anchor - expected)) < 1e-6


def test_run_holds_input_signals_after_their_last_row(tmp_path):
    # The anchor's x from 0 to 0.2 m over the table's one second, then held there to the end
    # (--help: "held before the first and after the last"), where it would go on at its slope of
    # 0.2 m/s to 0.4 m at 2 s if the last row did not stop it. The driven anchor is where the ramp
    # puts it to round-off of its position's arithmetic (1e-12 m against the 0.1 m of the error).
    (tmp_path / "ramp.csv").write_text("time,base.x\n0,0\n1,0.2\n")
    header, rows = run_csv(tmp_path, OSC, "--input", tmp_path / "ramp.csv", "--positions", "--t-end", "2",
                           "--output-interval", "0.5")
    x = rows[:, header.index("particle.anchor.x")]
    assert np.max(np.abs(x - [0, 0.1, 0.2, 0.2, 0.2])) < 1e-12, x


def test_run_moves_a_motion_port_at_the_slope_of_its_positions(tmp_path):
    # The anchor's x from 0 to 0.4 m over 2 s, no velocities given: it moves at the positions'
    # slope, v = 0.2 m/s (--help: "along the positions given (at their slope)"). In its frame the bob
    # starts with -v: M u'' = -K u, u(0) = x0 - l0, u'(0) = -v, u = (x0 - l0) cos(w t) - v / w sin(w t).
    # Held still between the rows it would stay at 0 and the bob would not see -v.
    # Tolerance as in test_run_takes_input_signals_as_closed_forms.
    w, v = math.sqrt(OSC_K / OSC_M), 0.2
    (tmp_path / "slide.csv").write_text("time,base.x\n0,0\n2,0.4\n")
    header, rows = run_csv(tmp_path, OSC, "--input", tmp_path / "slide.csv", *TIGHT_RUN)
    t, x = rows[:, 0], rows[:, header.index("tip.x")]
    u = (OSC_X0 - OSC_L0) * np.cos(w * t) - v / w * np.sin(w * t)
    assert len(t) == 21 and np.max(np.abs(x - (v * t + OSC_L0 + u))) < 1e-6
    # The anchor's force, K (L - l0) of the row's own state, to round-off (measured 1.8e-15 N),
    # where an anchor 1e-12 s behind the row's time is 1e-11 N off.
    f = rows[:, header.index("base.fx")]
    assert np.max(np.abs(f - OSC_K * (x - v * t - OSC_L0))) < 1e-12


@pytest.mark.parametrize("text, message", [
    ("time,tip.x\n0,1\n", '1:6: "tip.x" is an output: force port tip takes a force (.fx .fy .fz)'),
    ("time,base.fx\n0,1\n", '1:6: "base.fx" is an output: motion port base takes a position and velocity (.x .. .vz)'),
    ("time,nowhere.fx\n0,1\n", '1:6: "nowhere.fx" is no port\'s input'),
    ("time,tip.fx,tip.fx\n0,1,2\n", '1:13: "tip.fx" is named twice'),
    ("time,tip.fx\n0,1\n1,x\n", '3:3: "x" is not a finite decimal number'),
    ("time,tip.fx\n1,1\n0,2\n", "3:1: time 0 s is before the previous row's 1 s"),
    # The times as the file writes them, not 0.10000000000000001 and 0.20000000000000001.
    ("time,tip.fx\n0,1\n0.2,1\n0.1,2\n", "4:1: time 0.1 s is before the previous row's 0.2 s\n"),
    # A byte-order mark is refused even with nothing after it.
    ("\ufeff", "1:1: a byte-order mark before the header: write the file without one"),
    ("time,tip.fx\n", "2:1: no rows after the header"),
    ("time,tip.fx\n0,-1e308\n1e-300,1e308\n", "3:8: tip.fx: the slope from the row before is beyond a double"),
    # The column of the signal at fault, past one whose slope is finite.
    ("time,base.x,tip.fx\n0,0,-1e308\n1e-300,1,1e308\n",
     "3:10: tip.fx: the slope from the row before is beyond a double"),
    # A field longer than a message shows is cut at a character, and says so.
    ("time,tip.fx\n0," + "2" * 59 + "\u65e5\n", '2:3: "' + "2" * 59 + '"... is not a finite decimal number'),
    # One of just as many bytes as a message shows is shown whole, without the mark.
    ("time,tip.fx\n0," + "2" * 59 + "x\n", '2:3: "' + "2" * 59 + 'x" is not a finite decimal number'),
])
def test_run_refuses_input_signals_that_are_not_the_models(tmp_path, text, message):
    signals = tmp_path / "signals.csv"
    signals.write_text(text)
    err = cli("run", OSC, "-q", "-o", tmp_path / "out.csv", "--input", signals, status=1).stderr
    assert err.startswith(f"springmass run: --input {signals}:{message}"), err
    assert not (tmp_path / "out.csv").exists()
    # The output may not be the signals it reads.
    err = cli("run", OSC, "-q", "-o", signals, "--input", signals, status=2).stderr
    assert "the input signals" in err
    assert signals.read_text() == text


def test_run_refuses_input_signals_of_a_probe(tmp_path):
    # A probe's column is refused, not read and then left unapplied.
    signals = tmp_path / "signals.csv"
    signals.write_text("time,tip.x\n0,1\n")
    err = cli("run", MODELS / "hanging_rope.json", "-q", "-o", tmp_path / "out.csv", "--input", signals, status=1).stderr
    assert err.startswith(f'springmass run: --input {signals}:1:6: "tip.x" is a probe\'s: a probe takes no input'), err
    assert not (tmp_path / "out.csv").exists()


def test_run_reads_input_signals_from_a_regular_file_only(tmp_path):
    # As the model file: a FIFO without a writer is refused at once (it blocked the open for ever),
    # and so is a device, which would be read without end (/dev/zero filled the memory).
    fifo = tmp_path / "signals.csv"
    os.mkfifo(fifo)
    for signals in (fifo, "/dev/zero"):
        out = subprocess.run([str(CLI), "run", str(OSC), "-q", "-o", str(tmp_path / "out.csv"), "--input", str(signals)],
                             capture_output=True, text=True, timeout=10)
        assert out.returncode == 1
        assert out.stderr == f"springmass run: cannot read the input signals {signals}: not a regular file\n"
        assert not (tmp_path / "out.csv").exists()


def test_csv_numbers_are_the_shortest_text_that_reads_back_exactly(tmp_path):
    # 0.6 m is written 0.6, not 0.59999999999999998; a computed value with all 17 digits if it
    # needs them. In every CSV of run, statics and modes (after the particle and name columns).
    cli("run", MODELS / "two_mass_chain.json", "-q", "--t-end", 0.5, "--positions", "-o", tmp_path / "run.csv")
    cli("statics", MODELS / "hanging_rope.json", "-q", "-o", tmp_path / "statics.csv")
    cli("modes", MODELS / "oscillator.json", "-o", tmp_path / "modes.csv")
    for name, first in (("run.csv", 0), ("statics.csv", 2), ("modes.csv", 2)):
        with open(tmp_path / name, newline="") as f:
            fields = [x for row in list(csv.reader(f))[1:] for x in row[first:]]
        assert fields and [x for x in fields if x != shortest_text(float(x))] == [], name


# --- statics -----------------------------------------------------------------------------------

def test_statics_files_agree_and_the_rest_shape_is_an_equilibrium(tmp_path):
    rope = MODELS / "hanging_rope.json"
    out = cli("statics", rope, "-o", tmp_path / "rest.csv", "--vtk", tmp_path / "vtk",
              "--save-model", tmp_path / "rest.json").stdout
    assert re.search(r"stable\s+yes", out)
    header, rows = read_csv(tmp_path / "rest.csv")
    assert header == ["particle", "name", "x", "y", "z", "dx", "dy", "dz", "reaction_x", "reaction_y", "reaction_z"]
    x, dx, reaction = rows[:, 2:5], rows[:, 5:8], rows[:, 8:11]
    # Displacements from the initial positions (the rope along x from 0 to 1 m, 20 segments).
    x0 = np.column_stack([np.linspace(0, 1, 21), np.zeros(21), np.zeros(21)])
    np.testing.assert_allclose(dx, x - x0, rtol=0, atol=1e-15)
    # The largest motion is the free end's, from (1, 0, 0) m to below the pin (6 digits printed).
    motion = re.search(r"largest motion\s+(\S+) m at particle (\d+) \(rope\[20\]\)", out)
    assert int(motion.group(2)) == np.argmax(np.linalg.norm(dx, axis=1)) == 20
    assert float(motion.group(1)) == pytest.approx(np.linalg.norm(dx[20]), rel=1e-5)
    # Only the pinned end carries a reaction, and it holds the rope's weight (0.5 kg, g = 9.81):
    # the reaction is the force the supports exert, so it balances the weight to the solver's
    # tolerance (1e-9 N per particle).
    assert np.all(reaction[1:] == 0)
    np.testing.assert_allclose(reaction[0], [0, 0, 0.5 * 9.81], rtol=0, atol=1e-8)
    summary = re.search(r"reactions, sum\s+\(([^)]*)\)", out).group(1)
    np.testing.assert_allclose([float(v) for v in summary.split(",")], reaction[0], rtol=1e-8, atol=1e-12)
    # The weight is the file's total mass under its gravity, (0, 0, -0.5 * 9.81) N, to the 9
    # digits printed; the pin's row of the reaction table is the CSV's reaction.
    weight = re.search(r"weight\s+\(([^)]*)\)", out).group(1)
    np.testing.assert_allclose([float(v) for v in weight.split(",")], [0, 0, -0.5 * 9.81], rtol=1e-9, atol=0)
    pin = re.search(r"^0\s+rope\[0\]\s+(\S+)\s+(\S+)\s+(\S+)\s*$", out, re.M)
    np.testing.assert_allclose([float(v) for v in pin.groups()], reaction[0], rtol=1e-8, atol=1e-12)
    # The hanging rope is vertical below its pin, each segment stretched by the weight below it:
    # segment j carries (20 - j) m g with m = 0.5 / 21 kg, and its stiffness is E / l0 with
    # E = 2000 N, l0 = 0.05 m, so its length is l0 + (20 - j) m g l0 / E.
    m, l0 = 0.5 / 21, 0.05
    lengths = l0 + (20 - np.arange(20)) * m * 9.81 * l0 / 2000
    np.testing.assert_allclose(np.diff(x[:, 2]), -lengths, rtol=1e-9)
    np.testing.assert_allclose(x[:, :2], 0, atol=1e-9)
    # The VTK file carries the same shape (exactly), displacements and reactions (9 significant
    # digits).
    points, lines, vectors, _ = vtk_sections(tmp_path / "vtk" / "statics.vtk")
    assert lines == [(j, j + 1) for j in range(20)]
    assert np.array_equal(points, x)
    np.testing.assert_allclose(vectors["displacement"], dx, rtol=0, atol=1e-9)
    np.testing.assert_allclose(vectors["reaction"], reaction, rtol=0, atol=1e-8)
    # The saved model starts at rest in that shape: no Newton iteration is needed.
    again = cli("statics", tmp_path / "rest.json", "-q").stdout
    assert re.search(r"solver .*, 0 iterations", again), again
    # The sparse solver finds the same shape; one Newton iteration is not enough from the
    # horizontal rope; -q leaves out the per-particle table.
    sparse = cli("statics", rope, "--solver", "sparse", "-o", tmp_path / "sparse.csv").stdout
    assert "CHOLMOD" in sparse
    np.testing.assert_allclose(read_csv(tmp_path / "sparse.csv")[1][:, 2:5], x, rtol=0, atol=1e-9)
    cli("statics", rope, "--max-iterations", 1, status=1)
    # --tolerance is the largest force left on a free particle [N]: the default 1e-9 N and a looser
    # 1e-3 N are each reported and met, the looser one in no more Newton iterations.
    iterations = lambda text: int(re.search(r", (\d+) iterations", text).group(1))
    loose = cli("statics", rope, "-q", "--tolerance", 1e-3).stdout
    for text, tolerance in ((out, 1e-9), (loose, 1e-3)):
        assert number_after(text, "(tolerance") == pytest.approx(tolerance, rel=1e-3)  # 4 digits
        assert number_after(text, "residual") <= tolerance
    assert iterations(loose) <= iterations(out)
    # Where the automatic choice is the sparse solver (the tearing cloth, 399 unknowns), --solver
    # dense takes the dense one to the same rest shape: the same potential energy to the 9 digits
    # printed (both solves meet the 1e-9 N tolerance).
    cloth = MODELS / "tearing_cloth.json"
    auto, dense = (cli("statics", cloth, "-q", *options).stdout for options in ([], ["--solver", "dense"]))
    assert "CHOLMOD" in auto and "dense modified Cholesky" in dense, dense
    assert number_after(dense, "potential energy") == pytest.approx(number_after(auto, "potential energy"), rel=1e-8)
    quiet = cli("statics", rope, "-q").stdout
    assert len(quiet.splitlines()) < len(out.splitlines()) and "rope[0]" not in quiet and "rope[0]" in out


def run_into_a_pipe_without_a_reader(*args, env=None, pipe_signal_blocked=False):
    """Runs the tool with its standard output a pipe whose reader has gone (SIGPIPE at its
    default, as a shell leaves it, and blocked in the signal mask it starts with if
    pipe_signal_blocked); returns the finished process (text)."""
    read_end, write_end = os.pipe()
    os.close(read_end)
    block = (lambda: signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGPIPE})) if pipe_signal_blocked else None
    try:
        return subprocess.run([str(CLI), *map(str, args)], stdout=write_end, stderr=subprocess.PIPE, text=True,
                              env=env, timeout=60, preexec_fn=block)
    finally:
        os.close(write_end)


def test_statics_into_a_pipe_without_a_reader_leaves_no_temporary(tmp_path):
    # The saved model goes to standard output (/dev/stdout), whose reader has gone, after the CSV
    # and the VTK file were written under temporary names: the command ends by SIGPIPE, quietly
    # as at any write to such a pipe, and without leaving those temporaries behind (nor writing
    # the outputs, which are written all or none).
    out = run_into_a_pipe_without_a_reader("statics", MODELS / "two_mass_chain.json", "-q", "-o", tmp_path / "rest.csv",
                                           "--vtk", tmp_path / "vtk", "--save-model", "/dev/stdout")
    assert out.returncode == -signal.SIGPIPE and out.stderr == "", (out.returncode, out.stderr)
    assert sorted(str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*")) == ["vtk"]


def test_a_pipe_signal_blocked_from_the_start_makes_a_reader_gone_a_write_error(tmp_path):
    # Started with SIGPIPE blocked (a signal mask is inherited: a program that blocks it in the
    # thread that starts the tool passes it on), the tool is never ended by it: a write to a pipe
    # whose reader has gone is an output that cannot be written, named with the reason (exit
    # status 1), as with SIGPIPE ignored. It was a failure without a word: the failed write was
    # left to the signal to end the command quietly, and that signal, blocked, never came.
    out = run_into_a_pipe_without_a_reader("run", MODELS / "oscillator.json", "-q", "-o", "-", pipe_signal_blocked=True)
    assert out.returncode == 1 and out.stderr == "springmass run: cannot write standard output: Broken pipe\n", (
        out.returncode, out.stderr)
    # statics writes its outputs all or none: the saved model failing, the CSV is not written
    # either, and no temporary is left.
    out = run_into_a_pipe_without_a_reader("statics", MODELS / "two_mass_chain.json", "-q", "-o", tmp_path / "rest.csv",
                                           "--save-model", "/dev/stdout", pipe_signal_blocked=True)
    assert out.returncode == 1 and out.stderr == "springmass statics: cannot write /dev/stdout: Broken pipe\n", (
        out.returncode, out.stderr)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("command, options", [("statics", ["-q", "--save-model"]), ("modes", ["-o"])])
def test_outputs_into_a_pipe_without_a_reader_with_sigpipe_ignored_fail_to_write(tmp_path, command, options):
    # SIGPIPE ignored (by a program that starts the tool and handles a reader that goes away
    # itself): the write to standard output (/dev/stdout) whose reader has gone fails (EPIPE) and
    # ends nothing, so it is an output that cannot be written, named with its reason (exit status
    # 1), as run says it, not a failure without a word. The other outputs are not written (nor left
    # under temporary names).
    read_end, write_end = os.pipe()
    os.close(read_end)
    try:
        out = subprocess.run([str(CLI), command, str(MODELS / "two_mass_chain.json"), "--vtk", str(tmp_path / "vtk"),
                              *options, "/dev/stdout"], stdout=write_end, stderr=subprocess.PIPE, text=True,
                             timeout=60, restore_signals=False,
                             preexec_fn=lambda: signal.signal(signal.SIGPIPE, signal.SIG_IGN))
    finally:
        os.close(write_end)
    assert out.returncode == 1 and out.stderr == f"springmass {command}: cannot write /dev/stdout: Broken pipe\n", (
        out.returncode, out.stderr)
    assert [p for p in tmp_path.rglob("*") if not p.is_dir()] == []


def test_outputs_replaced_keep_their_permissions(tmp_path):
    # statics writes its outputs beside the files they replace and renames them over those: each
    # keeps the permissions of the file it replaced (0640 and 0600 here), as fopen's rewriting in
    # place would, not those of a new file (0644 under the umask 022 the tool is given here).
    csv_path, saved = tmp_path / "rest.csv", tmp_path / "saved.json"
    for path, mode in ((csv_path, 0o640), (saved, 0o600)):
        path.write_text("earlier\n")
        path.chmod(mode)
    out = subprocess.run([str(CLI), "statics", str(MODELS / "two_mass_chain.json"), "-q", "-o", str(csv_path),
                          "--save-model", str(saved)], capture_output=True, text=True, timeout=60,
                         preexec_fn=lambda: os.umask(0o022))
    assert out.returncode == 0, out.stderr
    assert read_csv(csv_path)[0][:2] == ["particle", "name"] and json.loads(saved.read_text())["name"] == "two_mass_chain"
    assert (csv_path.stat().st_mode & 0o7777, saved.stat().st_mode & 0o7777) == (0o640, 0o600)


def test_statics_prints_the_sum_of_the_loads_and_the_reactions_balance_it(tmp_path):
    # Two loads on one particle, (3, -4, 5) N and (1, 2, -20) N: the "loads" line is their sum,
    # every component, and the reaction at the anchor balances it with the weight of both
    # particles (the bob's 2 kg and the anchor's default 1 kg at 9.81 m/s^2): reactions =
    # -(loads + weight). Printed with 9 digits: 1e-9 N covers their rounding.
    model = tmp_path / "loaded.json"
    model.write_text(json.dumps({
        "springmass": 1, "name": "loaded", "gravity": [0, 0, -9.81],
        "particles": [{"name": "anchor", "position": [0, 0, 0], "fixed": True},
                      {"name": "bob", "position": [0, 0, -1], "mass": 2}],
        "springs": [{"a": "anchor", "b": "bob", "stiffness": 1000, "rest_length": 1}],
        "loads": [{"particle": "bob", "force": [3, -4, 5]}, {"particle": "bob", "force": [1, 2, -20]}]}))
    out = cli("statics", model).stdout

    def vector(label):
        match = re.search(re.escape(label) + r"\s+\(([^)]*)\) N", out)
        assert match, f"no '{label}' in:\n{out}"
        return [float(x) for x in match.group(1).split(",")]

    assert vector("loads") == [4.0, -2.0, -15.0]
    np.testing.assert_allclose(vector("weight"), [0.0, 0.0, -29.43], rtol=0, atol=1e-9)
    np.testing.assert_allclose(vector("reactions, sum"), [-4.0, 2.0, 44.43], rtol=0, atol=1e-9)
    # The model line counts its one spring, and the solver line the oscillator's one iteration, in
    # the singular.
    assert "(2 particles, 1 free, 1 spring)" in out
    assert re.search(r"^solver .*, \d+ iterations?$", out, re.M)
    assert "1 iterations" not in cli("statics", MODELS / "oscillator.json").stdout


def test_statics_balances_each_particle_to_its_own_tolerance(tmp_path):
    # A 1 kg bob hanging on a stiff spring beside a separate 1 ug bob on a soft one, each under its
    # own fixed anchor. The default tolerance is 1e-9 N at the heavy bob (1e-6 of its 9.81 N weight
    # is more) and 1e-6 of its own 9.81e-9 N weight at the light one: the "balance" line names the
    # particle nearest to its own tolerance, with its force within it. The light bob hangs
    # m g / k = 9.81e-3 m below its rest length, to its tolerance over its stiffness,
    # 9.81e-15 N / 1e-6 N/m ~ 1e-8 m.
    model = tmp_path / "light.json"
    model.write_text(json.dumps({
        "springmass": 1, "name": "light", "gravity": [0, 0, -9.81],
        "particles": [{"name": "anchor", "position": [0, 0, 0], "fixed": True},
                      {"name": "heavy", "position": [0, 0, -1], "mass": 1},
                      {"name": "hook", "position": [1, 0, 0], "fixed": True},
                      {"name": "light", "position": [1, 0, -1], "mass": 1e-9}],
        "springs": [{"a": "anchor", "b": "heavy", "stiffness": 1e7, "rest_length": 1},
                    {"a": "hook", "b": "light", "stiffness": 1e-6, "rest_length": 1}]}))
    out = cli("statics", model, "-o", tmp_path / "shape.csv").stdout
    match = re.search(r"^balance +particle (\d+) \((\w+)\) nearest to its tolerance: (\S+) N of (\S+) N$", out, re.M)
    assert match, out
    assert float(match.group(3)) <= float(match.group(4))
    header, rows = read_csv(tmp_path / "shape.csv")
    assert rows[3, header.index("z")] == pytest.approx(-(1 + 9.81e-9 / 1e-6), rel=0, abs=1e-8)


def test_statics_out_of_iterations_gives_the_force_left_without_a_particle_name():
    # The bundled cloth after 2 Newton iterations (it needs 125) has 20 N left on a free particle.
    # The tool names the particle of every "particle N" in a message; the force must not read as
    # one: "particle 20 (cloth[1,4]) N" named particle 20, which has nothing to do with it.
    err = cli("statics", MODELS / "cloth.json", "--max-iterations", 2, "-q", status=1).stderr
    assert "(cloth[" not in err, err
    assert re.search(r"the largest force on a free particle is [0-9.e+-]+ N > tolerance 1e-09 N", err), err


def test_statics_messages_name_the_options_not_the_library_fields():
    # The library's messages name sm_statics_def's fields; the tool's user typed options.
    err = cli("statics", MODELS / "cloth.json", "--max-iterations", 2, "-q", status=1).stderr
    assert "no equilibrium found in 2 iterations (--max-iterations):" in err, err
    # A tolerance at or above the largest load is refused as any other value outside what the help
    # allows ("below the largest load on one"): a usage error, status 2, not a bad model's 1.
    err = cli("statics", MODELS / "cloth.json", "--tolerance", 100, "-q", status=2).stderr
    assert f"springmass statics: {MODELS / 'cloth.json'}: --tolerance 100 N is not below the largest load on a free particle" in err, err
    assert "residual_tolerance" not in err and "max_iterations" not in err


def test_statics_names_the_springs_its_rest_shape_would_break(tmp_path):
    # Two 1 kg bobs hang in a chain from a fixed anchor on springs of 100 N/m and rest length 1 m,
    # g = 10 m/s^2: the upper spring carries 20 N, strain 0.2; the lower one 10 N, strain 0.1. With
    # break strains 0.1 and 0.5, the upper one is at twice its own and the lower one within: statics
    # says so of the upper one alone, and nothing when both are within theirs.
    chain = {"springmass": 1, "name": "chain", "gravity": [0, 0, -10],
             "particles": [{"name": "anchor", "position": [0, 0, 0], "fixed": True, "mass": 1},
                           {"name": "b1", "position": [0, 0, -1], "mass": 1},
                           {"name": "b2", "position": [0, 0, -2], "mass": 1}],
             "springs": [{"a": "anchor", "b": "b1", "stiffness": 100, "rest_length": 1, "break_strain": 0.1},
                         {"a": "b1", "b": "b2", "stiffness": 100, "rest_length": 1, "break_strain": 0.5}]}
    path = tmp_path / "chain.json"
    path.write_text(json.dumps(chain))
    line = summary_line(cli("statics", path, "-q").stdout, "break strains")
    assert line == ("1 spring(s) at or beyond theirs, which a simulation would break; the furthest, at 2 times its "
                    "break strain: spring 0 (between anchor and b1)"), line
    # check counts both springs as breakable.
    assert summary_line(cli("check", path).stdout, "springs").endswith("2 breakable")
    chain["springs"][0]["break_strain"] = 0.5
    path.write_text(json.dumps(chain))
    assert "break strains" not in cli("statics", path, "-q").stdout
    # Exactly at its break strain (both ends held 1.5 m apart, rest length 1 m, break strain 0.5:
    # L = l0 (1 + strain) without rounding), a spring breaks at the start of a simulation, and
    # statics says so.
    held = {"springmass": 1, "name": "held", "gravity": [0, 0, 0],
            "particles": [{"name": "a", "position": [0, 0, 0], "fixed": True, "mass": 1},
                          {"name": "b", "position": [1.5, 0, 0], "fixed": True, "mass": 1}],
            "springs": [{"a": "a", "b": "b", "stiffness": 100, "rest_length": 1, "break_strain": 0.5}]}
    path.write_text(json.dumps(held))
    assert "spring 0 (between a and b) broke at t = 0 s" in cli("run", path, "--t-end", "0.1", "-o", "-").stderr
    line = summary_line(cli("statics", path, "-q").stdout, "break strains")
    assert line.startswith("1 spring(s) at or beyond theirs") and "at 1 times" in line, line
    # The supports' reactions along y and z are zero, printed as 0, not -0.
    reactions = cli("statics", path).stdout.split("reaction z [N]")[1].split()
    assert reactions == ["0", "a", "-50", "0", "0", "1", "b", "50", "0", "0"], reactions


# --- modes -------------------------------------------------------------------------------------

def mode_table(text):
    """Rows (mode, frequency [Hz], period [s], omega^2 [1/s^2], damping ratio) of `modes`; the
    period of a zero mode reads as inf."""
    number = r"\s+([-0-9.e+]+|inf)"
    rows = re.findall(r"^\s+(\d+)" + 4 * number + r"\s*$", text, re.M)
    return np.array([[float(v) for v in row] for row in rows])


def test_modes_of_the_oscillator_follow_the_closed_form(tmp_path):
    # A bob of mass m on a spring of stiffness k, rest length l0 = 0.5 m, stretched to L = 0.6 m:
    # along the spring omega^2 = k / m; across it the spring acts with k (1 - l0 / L) (its
    # tension over its length), twice (y and z). Spring damping d acts along the spring only:
    # damping ratio d / (2 sqrt(k m)) there, 0 across. The table prints 9 digits.
    m, k, d = 4.0, 40.0, 0.4
    out = cli("modes", MODELS / "oscillator.json", "--set", f"m={m}", "--steps-per-period", 20,
              "-o", tmp_path / "modes.csv", "--vtk", tmp_path / "vtk").stdout
    table = mode_table(out)
    omega2 = np.array([k * (1 - 0.5 / 0.6), k * (1 - 0.5 / 0.6), k]) / m
    np.testing.assert_allclose(table[:, 3], omega2, rtol=1e-8)
    np.testing.assert_allclose(table[:, 1], np.sqrt(omega2) / (2 * math.pi), rtol=1e-8)
    np.testing.assert_allclose(table[:, 2], 1 / table[:, 1], rtol=1e-8)
    # (Damping ratios are printed to 6 significant digits.)
    np.testing.assert_allclose(table[:, 4], [0, 0, d / (2 * math.sqrt(k * m))], rtol=5e-6, atol=1e-12)
    # A communication step of a twentieth of the highest mode's period (6 significant digits).
    step = number_after(out, "communication step       <=")
    assert step == pytest.approx(2 * math.pi / math.sqrt(k / m) / 20, rel=1e-5)
    # The highest mode is the axial one: omega_max = sqrt(k / m), in Hz divided by 2 pi (9 digits),
    # and the explicit stability limit 2 / omega_max (6 digits).
    assert number_after(out, "omega_max =") == pytest.approx(math.sqrt(k / m), rel=1e-8)
    assert number_after(out, "highest frequency") == pytest.approx(math.sqrt(k / m) / (2 * math.pi), rel=1e-8)
    assert number_after(out, "2/omega_max =") == pytest.approx(2 / math.sqrt(k / m), rel=1e-5)
    # The explicit stability limit with the damping rate d / m of the bob's one spring (its
    # anchor is fixed): symplectic Euler's 2 / (gamma/2 + sqrt(gamma^2/4 + omega^2)).
    gamma = d / m
    limit = 2 / (gamma / 2 + math.sqrt(gamma**2 / 4 + k / m))
    assert number_after(out, "explicit stability limit") == pytest.approx(limit, rel=1e-5)
    # Mass-normalised shapes: the axial mode moves the bob along x by 1 / sqrt(m), the others
    # across (y, z); the anchor does not move.
    header, shapes = read_csv_with_names(tmp_path / "modes.csv")
    assert header == ["particle", "name"] + [f"mode{j}_{c}" for j in (1, 2, 3) for c in "xyz"]
    bob = shapes["bob"]
    assert np.allclose(shapes["anchor"], 0)
    assert abs(bob[6]) == pytest.approx(1 / math.sqrt(m), rel=1e-12) and np.allclose(bob[7:9], 0, atol=1e-15)
    for mode in (0, 1):
        shape = bob[3 * mode:3 * mode + 3]
        assert shape[0] == pytest.approx(0, abs=1e-15) and np.linalg.norm(shape) == pytest.approx(1 / math.sqrt(m))
    # One VTK file per mode, with the CSV's shape and the mode's frequency in its title.
    for mode in range(3):
        path = tmp_path / "vtk" / f"mode_{mode + 1}.vtk"
        assert f"{table[mode, 1]:.6g}"[:6] in open(path).read().split("\n")[1]
        _, _, vectors, _ = vtk_sections(path)
        np.testing.assert_allclose(vectors["shape"][1], bob[3 * mode:3 * mode + 3], rtol=0, atol=1e-9)
    assert sorted(p.name for p in (tmp_path / "vtk").iterdir()) == ["mode_1.vtk", "mode_2.vtk", "mode_3.vtk"]


def test_a_shorter_series_removes_what_a_longer_one_left(tmp_path):
    # modes: 3 modes after 5 leave mode_1 to mode_3, which ParaView would otherwise open with the
    # earlier run's mode_4 and mode_5 as one group; a file of that name that is not a VTK file
    # (here mode_7, past a gap) is not touched, nor a symbolic link (mode_9, after a mode_8).
    vtk = tmp_path / "vtk"
    cli("modes", MODELS / "hanging_rope.json", "-n", 5, "--vtk", vtk)
    (vtk / "mode_7.vtk").write_text("notes\n")
    out = cli("modes", MODELS / "hanging_rope.json", "-n", 3, "--vtk", vtk).stdout
    assert f"removed {vtk}/mode_4.vtk to mode_5.vtk" in out
    assert sorted(p.name for p in vtk.iterdir()) == ["mode_1.vtk", "mode_2.vtk", "mode_3.vtk", "mode_7.vtk"]
    shutil.copy(vtk / "mode_1.vtk", tmp_path / "kept.vtk")
    shutil.copy(vtk / "mode_1.vtk", vtk / "mode_8.vtk")
    (vtk / "mode_9.vtk").symlink_to(tmp_path / "kept.vtk")
    (vtk / "mode_7.vtk").unlink()
    out = cli("modes", MODELS / "hanging_rope.json", "-n", 7, "--vtk", vtk).stdout
    assert f"removed {vtk}/mode_8.vtk, left there by an earlier run with more modes" in out
    assert (vtk / "mode_9.vtk").is_symlink() and (tmp_path / "kept.vtk").exists()
    # run: 6 rows after 11 (t = 0 to 1 s every 0.1 s, then every 0.2 s); the index names the six.
    model = MODELS / "oscillator.json"
    cli("run", model, "-q", "-o", tmp_path / "a.csv", "--t-end", 1, "--output-interval", 0.1, "--vtk", vtk)
    assert len(list(vtk.glob("oscillator_*.vtp"))) == 11
    err = cli("run", model, "-o", tmp_path / "b.csv", "--t-end", 1, "--output-interval", 0.2, "--vtk", vtk).stderr
    assert "removed oscillator_000006.vtp to oscillator_000010.vtp of an earlier run" in err
    index = ET.parse(vtk / "oscillator.pvd").getroot()
    assert sorted(p.name for p in vtk.glob("oscillator_*.vtp")) == [
        d.get("file") for d in index.findall("./Collection/DataSet")] == [f"oscillator_{k:06d}.vtp" for k in range(6)]


def test_modes_show_the_progress_of_a_long_lanczos_iteration():
    # The lowest 10 modes of a 129 x 129 trampoline (48 387 degrees of freedom) take about 2 s:
    # into a pipe, the progress line comes as the last line on stderr once the work took over a
    # second. The last Lanczos cycle has converged every mode it sought (10 and the next one).
    start = time.monotonic()
    out = cli("modes", MODELS / "trampoline.json", "--set", "n=129", "-n", 10)
    wall = time.monotonic() - start
    lines = re.findall(r"springmass modes: Lanczos step (\d+), (\d+) of (\d+) modes converged in this run, "
                       r"([0-9.]+) s", out.stderr)
    if wall > 1.5:
        step, converged, sought, seconds = lines[-1]
        assert int(step) > 0 and converged == sought == "11" and 1.0 <= float(seconds) <= wall + 0.05  # printed to 0.1 s: 1.04 s is 1.0
    elif wall < 0.9:
        assert lines == []


def read_csv_with_names(path):
    """(header, {name: the numbers after the name}) of a CSV whose first two columns are an index
    and a name."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], {r[1]: np.array([float(v) for v in r[2:]]) for r in rows[1:]}


def test_modes_about_the_rest_shape_are_those_of_a_hanging_chain(tmp_path):
    rope = MODELS / "hanging_rope.json"
    # Default count: the 10 lowest of the 60; -n 0: all of them, in increasing order.
    initial = mode_table(cli("modes", rope).stdout)
    assert len(initial) == 10
    everything = mode_table(cli("modes", rope, "-n", 0).stdout)
    assert len(everything) == 60 and np.all(np.diff(everything[:, 3]) >= 0)
    # About the rest shape, the swinging modes of a hanging chain: a segment of tension T and
    # length L resists a sideways offset of its ends with stiffness T / L, so the lowest modes
    # solve K y = omega^2 M y with K the tridiagonal matrix of the T_j / L_j (the tensions and
    # lengths from the rest shape that statics writes) and M the 20 free masses, 0.5 / 21 kg
    # each; they come twice (x and y). Mass damping alpha = 0.1 1/s gives damping ratios
    # alpha / (2 omega). Both sides start from the statics solution (residual 1e-9 N), printed
    # to 9 significant digits: they agree to about 1e-8 (1e-7 allowed).
    cli("statics", rope, "-q", "-o", tmp_path / "rest.csv")
    _, rest = read_csv(tmp_path / "rest.csv")
    z = rest[:, 4]
    m = 0.5 / 21
    lengths = -np.diff(z)
    tension = (20 - np.arange(20)) * m * 9.81
    stiffness = tension / lengths
    # Free particle i + 1 hangs from segment i and holds segment i + 1 (particle 0 is pinned).
    K = np.diag(np.append(stiffness[:-1] + stiffness[1:], stiffness[-1]))
    for j in range(19):
        K[j, j + 1] = K[j + 1, j] = -stiffness[j + 1]
    omega2 = np.sort(np.linalg.eigvalsh(K / m))[:5]
    table = mode_table(cli("modes", rope, "--at-equilibrium", "-n", 10).stdout)
    swinging = table[:, 3]
    np.testing.assert_allclose(swinging[0::2][:5], omega2, rtol=1e-7)
    np.testing.assert_allclose(swinging[1::2][:5], omega2, rtol=1e-7)
    np.testing.assert_allclose(table[:, 4], 0.1 / (2 * np.sqrt(swinging)), rtol=5e-6)  # 6 digits
    assert not np.allclose(table[:, 3], initial[:, 3], rtol=1e-2)
    # The sparse eigensolver (shift-invert Lanczos) finds the lowest modes of the same problem:
    # the dense solver's, to the residual of both (about 1e-12 relative; 1e-8 allowed).
    sparse = cli("modes", rope, "--at-equilibrium", "--solver", "sparse", "-n", 4).stdout
    assert "shift-invert Lanczos" in sparse, sparse
    np.testing.assert_allclose(mode_table(sparse)[:, 3], table[:4, 3], rtol=1e-8)


def test_modes_of_a_membrane_pretensioned_by_its_rest_lengths_are_a_taut_grids(tmp_path):
    # docs/model-format.md: a sheet without spring groups keeps its particles and masses, and its
    # springs listed in `springs` with rest lengths l0 shorter than the spacing h pre-tension it:
    # per section (section h, h / 2 along an edge), the tension is Y (h / l0 - 1) per unit width.
    # Held along its edges, flat, the 1 m square of 1 kg/m^2 (lumped: h^2 per inner particle)
    # vibrates across its plane as a taut grid, each inner particle pulled towards its four
    # neighbours with T / h per metre of their offset: omega^2 = T / (rho h^2) (4 sin^2(i pi /
    # (2 N)) + 4 sin^2(j pi / (2 N))), N = 8 cells a side, modes (i, j) and (j, i) alike; its
    # in-plane modes, stiffened by the springs' own Y h / l0, lie far above the six lowest. The
    # table prints 9 digits.
    n, cells, Y, l0 = 9, 8, 1000.0, 0.95 / 8
    h = 1.0 / cells
    springs = []
    for i in range(n):
        for j in range(n):
            if j + 1 < n:
                springs.append({"a": f"membrane[{i},{j}]", "b": f"membrane[{i},{j + 1}]", "section_stiffness": "Y",
                                "section": h / 2 if i in (0, n - 1) else h, "rest_length": l0})
            if i + 1 < n:
                springs.append({"a": f"membrane[{i},{j}]", "b": f"membrane[{i + 1},{j}]", "section_stiffness": "Y",
                                "section": h / 2 if j in (0, n - 1) else h, "rest_length": l0})
    edges = [([-0.01, -0.01, -0.01], [0.01, 1.01, 0.01]), ([0.99, -0.01, -0.01], [1.01, 1.01, 0.01]),
             ([-0.01, -0.01, -0.01], [1.01, 0.01, 0.01]), ([-0.01, 0.99, -0.01], [1.01, 1.01, 0.01])]
    model = {"springmass": 1, "name": "membrane", "parameters": {"Y": Y}, "gravity": [0, 0, 0],
             "structures": [{"type": "sheet", "name": "membrane", "nu": n, "nv": n, "mass": 1.0,
                             "mass_distribution": "lumped"}],
             "springs": springs, "fixed": [{"min": a, "max": b} for a, b in edges]}
    (tmp_path / "membrane.json").write_text(json.dumps(model))
    table = mode_table(cli("modes", tmp_path / "membrane.json", "-n", 6).stdout)
    tension = Y * (h / l0 - 1)
    s = [4 * math.sin(k * math.pi / (2 * cells)) ** 2 for k in range(1, cells)]
    omega2 = sorted(tension / h**2 * (s[i] + s[j]) for i in range(cells - 1) for j in range(cells - 1))[:6]
    np.testing.assert_allclose(table[:, 3], omega2, rtol=1e-8)


def test_modes_count_unstable_and_zero_modes(tmp_path):
    # A 2 kg bob held by an 8 N/m spring of rest length 2 m compressed to 1 m: along the spring
    # omega^2 = k / m = 4 1/s^2 (period pi s); across it the spring pushes, omega^2 = k (1 - l0 / L) / m
    # = -4 1/s^2, twice: two unstable modes, which have no period. A particle without springs has
    # three zero modes, of infinite period.
    bob = {"springmass": 1, "name": "bob", "gravity": [0, 0, 0],
           "particles": [{"name": "anchor", "position": [0, 0, 0], "fixed": True},
                         {"name": "bob", "position": [1, 0, 0], "mass": 2}],
           "springs": [{"a": "anchor", "b": "bob", "stiffness": 8, "rest_length": 2}]}
    (tmp_path / "bob.json").write_text(json.dumps(bob))
    out = cli("modes", tmp_path / "bob.json", "--vtk", tmp_path / "vtk").stdout
    assert summary_line(out, "zero modes").startswith("0 (") and summary_line(out, "unstable modes").startswith("2 (")
    # Linearised about its initial configuration, which is no rest shape: the unstable modes send to
    # --at-equilibrium, and with no zero mode the zero modes' line has no word on mechanisms.
    assert summary_line(out, "unstable modes") == \
        "2 (omega^2 < 0: the configuration is not a stable rest shape; try --at-equilibrium)"
    assert summary_line(out, "zero modes").endswith("soft to resolve, see --zero-tolerance)")
    # The VTK files' titles (their second line) say the same, not a frequency of 0 Hz.
    titles = [(tmp_path / "vtk" / f"mode_{m}.vtk").read_text().split("\n")[1] for m in (1, 2, 3)]
    assert titles[0].startswith("springmass mode 1, unstable: omega^2 = -4") and titles[0].endswith(" 1/s^2")
    assert titles[2] == "springmass mode 3, 0.318309886 Hz"  # 2 / (2 pi), 9 digits
    rows = re.findall(r"^\s+\d+\s+(\S+)\s+(\S+)\s+(\S+)\s+\S+\s*$", out, re.M)
    assert [period for _, period, _ in rows] == ["unstable", "unstable", "3.14159265"]  # 9 digits
    np.testing.assert_allclose([float(w2) for _, _, w2 in rows], [-4, -4, 4], rtol=1e-12)
    # An unstable mode has no damping ratio ("-"); the undamped axial one's is 0.
    assert re.findall(r"^\s+\d+\s+\S+\s+\S+\s+\S+\s+(\S+)\s*$", out, re.M) == ["-", "-", "0"]
    free = {"springmass": 1, "name": "free", "gravity": [0, 0, 0], "particles": [{"name": "p", "position": [0, 0, 0]}]}
    (tmp_path / "free.json").write_text(json.dumps(free))
    out = cli("modes", tmp_path / "free.json", "--vtk", tmp_path / "free_vtk").stdout
    assert summary_line(out, "zero modes").startswith("3 (") and "unstable modes" not in out
    assert summary_line(out, "zero modes").endswith(
        "see --zero-tolerance; where the rest shape is stretched, --at-equilibrium gives mechanisms their stiffness)")
    # A zero mode is not unstable: its file's title gives its frequency, 0 Hz.
    titles = [(tmp_path / "free_vtk" / f"mode_{m}.vtk").read_text().split("\n")[1] for m in (1, 2, 3)]
    assert titles == [f"springmass mode {m}, 0 Hz" for m in (1, 2, 3)]
    assert [period for _, period, _ in re.findall(r"^\s+\d+\s+(\S+)\s+(\S+)\s+(\S+)\s+\S+\s*$", out, re.M)] == 3 * ["inf"]



def test_modes_say_what_their_zero_level_is_relative_to(tmp_path):
    # The dense solver sets |omega^2| <= 1e-12 of the largest eigenvalue to 0; the sparse one, which
    # computes only the lowest modes, 1e-12 of the Gershgorin bound omega_max^2 (docs/analysis.md).
    # A free 4 x 4 x 4 block (192 degrees of freedom, enough for the sparse solver): six zero modes.
    block = {"springmass": 1, "name": "block", "gravity": [0, 0, 0],
             "structures": [{"type": "block", "name": "b", "size": [1, 1, 1], "nu": 4, "nv": 4, "nw": 4,
                             "edge": {"strain_stiffness": 300}, "face_diagonal": {"strain_stiffness": 300}}]}
    (tmp_path / "block.json").write_text(json.dumps(block))
    dense = summary_line(cli("modes", tmp_path / "block.json", "--solver", "dense").stdout, "zero modes")
    sparse = summary_line(cli("modes", tmp_path / "block.json", "--solver", "sparse").stdout, "zero modes")
    assert dense.startswith("6 (|omega^2| <= 1e-12 of the largest:"), dense
    assert sparse.startswith("6 among the modes listed (|omega^2| <= 1e-12 of the Gershgorin bound"), sparse


def test_modes_take_the_ends_of_the_ranges_their_options_allow():
    # --zero-tolerance takes [0, 1): 0 itself, where only an omega^2 of exactly 0 is a zero mode,
    # and not 1. --steps-per-period takes any finite number >= 1: 1 itself suggests a communication
    # step of the highest listed mode's whole period (6 digits printed; the frequency 9).
    osc = MODELS / "oscillator.json"
    out = cli("modes", osc, "--zero-tolerance", 0).stdout
    assert summary_line(out, "zero modes").startswith("0 (|omega^2| <= 0 of the largest:"), out
    err = cli("modes", osc, "--zero-tolerance", 1, status=2).stderr
    assert err == "springmass modes: --zero-tolerance needs a number in [0, 1), got '1'\n"
    out = cli("modes", osc, "--steps-per-period", 1).stdout
    highest = number_after(out, "highest frequency")
    assert summary_line(out, "communication step").endswith(
        f"(1/1 of the period of the highest mode listed, {highest:.6g} Hz)")
    assert number_after(out, "communication step       <=") == pytest.approx(1 / highest, rel=1e-5)


def test_modes_that_lanczos_cannot_converge_point_to_the_dense_solver():
    # A cloth 1e6 times stiffer than the bundled one, at its equilibrium: its lowest modes lie at
    # about 1e-13 of the Gershgorin bound, at the round-off of the stiffness, where shift-invert
    # Lanczos does not converge; the dense solver resolves them (as seven zeros).
    args = ("modes", MODELS / "cloth.json", "--at-equilibrium", "--set", "E=1e9", "-n", 3)
    failed = cli(*args, status=1)
    assert "Lanczos did not converge" in failed.stderr, failed.stderr
    assert "the dense solver resolves them (SM_MODES_DENSE, springmass modes --solver dense)" in failed.stderr
    assert summary_line(cli(*args, "--solver", "dense").stdout, "zero modes").startswith("7 (")


def test_modes_say_when_the_list_ends_inside_a_repeated_frequency(tmp_path):
    # The trampoline at equilibrium has a pair of modes at 7.885 Hz, modes 2 and 3: -n 2 ends
    # inside it and says so under the table, -n 1 and -n 3 end between frequencies and do not.
    # The groups of zero and unstable modes are cut alike: a free particle's three zero modes at
    # -n 2, and the compressed bob's two unstable ones (as in the test above) at -n 1, not at -n 2.
    note = re.compile(r"mode (\d+)'s frequency repeats in mode (\d+)")
    for n, cut in ((1, False), (2, True), (3, False)):
        out = cli("modes", MODELS / "trampoline.json", "--at-equilibrium", "-n", n).stdout
        assert [m.groups() for m in note.finditer(out)] == ([(str(n), str(n + 1))] if cut else []), out
    bob = {"springmass": 1, "name": "bob", "gravity": [0, 0, 0],
           "particles": [{"name": "anchor", "position": [0, 0, 0], "fixed": True},
                         {"name": "bob", "position": [1, 0, 0], "mass": 2}],
           "springs": [{"a": "anchor", "b": "bob", "stiffness": 8, "rest_length": 2}]}
    free = {"springmass": 1, "name": "free", "gravity": [0, 0, 0], "particles": [{"name": "p", "position": [0, 0, 0]}]}
    for model, n, cut in ((bob, 1, True), (bob, 2, False), (free, 2, True), (free, 3, False)):
        path = tmp_path / f"{model['name']}.json"
        path.write_text(json.dumps(model))
        assert bool(note.search(cli("modes", path, "-n", n).stdout)) == cut, (model["name"], n)

# --- check -------------------------------------------------------------------------------------

def summary_line(text, label):
    match = re.search(r"^\s*" + re.escape(label) + r"\s+(.*)$", text, re.M)
    assert match, f"no '{label}' line in:\n{text}"
    return match.group(1)


@pytest.mark.parametrize("model", sorted(p.name for p in MODELS.glob("*.json")))
def test_check_bounds_the_highest_frequency(model):
    # check's omega_max is an upper bound (Gershgorin's, over the springs' stiffness, which holds at
    # any positions): never below the exact highest frequency of the dense eigenproblem that
    # `modes -n 0` solves, so the stability limit check prints is a safe step. Both print 6 or
    # more digits: the comparison allows for the last one.
    bound = number_after(cli("check", MODELS / model).stdout, "omega_max    <=")
    modes = cli("modes", MODELS / model, "-n", "0").stdout
    if "omega_max =" in modes:
        assert bound >= number_after(modes, "omega_max =") * (1 - 1e-5)


def test_stability_limit_of_a_damped_oscillator(tmp_path):
    # A 1 kg bob on a 100 N/m spring at its rest length with a 40 N s/m dashpot: omega = 10 rad/s,
    # zeta = 40 / (2 sqrt(100)) = 2. Symplectic Euler (v += h a(x, v), then x += h v), the scheme
    # the limit is printed for, maps (x, v) by [[1 - w^2 h^2, h (1 - 2 zeta w h)], [-w^2 h,
    # 1 - 2 zeta w h]]: determinant 1 - 2 zeta w h, trace 2 - w^2 h^2 - 2 zeta w h; both
    # eigenvalues lie in the unit circle (Jury) for w h <= 2 (sqrt(1 + zeta^2) - zeta), here
    # 0.0472 s, a quarter of the undamped 2 / omega = 0.2 s. A step the tools call the limit, or a
    # bound below it, must be stable: at most that step (6 digits printed: 1e-5 allowed).
    bob = {"springmass": 1, "name": "bob", "gravity": [0, 0, 0],
           "particles": [{"name": "anchor", "position": [0, 0, 0], "fixed": True},
                         {"name": "bob", "position": [1, 0, 0], "mass": 1}],
           "springs": [{"a": "anchor", "b": "bob", "stiffness": 100, "damping": 40, "rest_length": 1}]}
    path = tmp_path / "bob.json"
    path.write_text(json.dumps(bob))
    omega, zeta = 10.0, 2.0
    stable = 2 * (math.sqrt(1 + zeta**2) - zeta) / omega
    # Here the bounds are exact (one mode along the spring carries all of the stiffness and the
    # damping): modes prints 6 digits, check 3.
    assert number_after(cli("modes", path, "-n", "0").stdout, "explicit stability limit") == pytest.approx(
        stable, rel=1e-5)
    assert number_after(cli("check", path).stdout, "steps up to at least") == pytest.approx(stable, rel=2e-3)
    # check prints the damping rate it bounds, here exactly the dashpot's d / m = 40 1/s (3 digits);
    # modes, with every mode at hand, takes each mode's own rate (test_analysis covers the bound's
    # branch, with fewer modes kept).
    assert number_after(cli("check", path).stdout, "damping rate <=") == pytest.approx(40, rel=2e-3)
    assert "each mode with its own damping rate" in cli("modes", path, "-n", "0").stdout
    # Each printed limit is stable: symplectic Euler on the bob at that step decays (the check is
    # the scheme itself, 2000 steps from x = 1e-3 m off rest), and at 1.1 times it blows up.
    def final_amplitude(h):
        x, v = 1e-3, 0.0
        for _ in range(2000):
            v += h * (-omega**2 * x - 2 * zeta * omega * v)
            x += h * v
        return abs(x) + abs(v) * h
    assert final_amplitude(stable * 0.999) < 1e-3 and final_amplitude(stable * 1.1) > 1.0
    # Mass damping alone (no spring stiffness along the motion, alpha = 4 1/s): 2 / alpha = 0.5 s.
    bob["springs"][0].update(stiffness=0, damping=0)
    bob["mass_damping"] = 4.0
    path.write_text(json.dumps(bob))
    assert number_after(cli("check", path).stdout, "steps up to at least") == pytest.approx(0.5, rel=2e-3)
    modes = cli("modes", path, "-n", "0").stdout
    assert number_after(modes, "explicit stability limit") == pytest.approx(0.5, rel=1e-5)
    assert "no stiffness" in modes and "inf" not in summary_line(modes, "explicit stability limit")
    # Neither stiffness nor damping: nothing limits the step, and neither tool prints one.
    bob["mass_damping"] = 0.0
    path.write_text(json.dumps(bob))
    assert "explicit" not in cli("check", path).stdout
    assert "explicit" not in cli("modes", path, "-n", "0").stdout


def test_stability_limit_without_frequencies_names_the_damping_rate_it_comes_from(tmp_path):
    # Two free particles of 1 and 4 kg joined by a dashpot of 1 N s/m without stiffness: every
    # omega^2 is 0, and the one damped mode, the particles moving apart along the dashpot, decays
    # at the rate d (1/m1 + 1/m2) = 1.25 1/s; undamped, symplectic Euler's limit for a damping
    # rate gamma alone is 2 / gamma. With every mode listed the limit is that mode's own, 1.6 s;
    # with fewer, the Gershgorin bound d (1/m1 + 1/sqrt(m1 m2)) = 1.5 1/s gives 2 / 1.5 s. The
    # rate a line names is the one its step comes from (6 digits printed: 1e-5 allowed).
    pair = {"springmass": 1, "name": "pair", "gravity": [0, 0, 0],
            "particles": [{"name": "a", "position": [0, 0, 0], "mass": 1},
                          {"name": "b", "position": [1, 0, 0], "mass": 4}],
            "springs": [{"a": "a", "b": "b", "stiffness": 0, "damping": 1, "rest_length": 1}]}
    path = tmp_path / "pair.json"
    path.write_text(json.dumps(pair))
    every = summary_line(cli("modes", path, "-n", "0").stdout, "explicit stability limit")
    assert number_after(every, "") == pytest.approx(2 / 1.25, rel=1e-5)
    assert "each mode with its own damping rate" in every and "<=" not in every, every
    fewer = summary_line(cli("modes", path, "-n", "2").stdout, "explicit stability limit")
    assert number_after(fewer, "") == pytest.approx(2 / 1.5, rel=1e-5)
    assert number_after(fewer, "damping rate <=") == pytest.approx(1.5, rel=1e-5)
    # A bob squeezed by six dashpot springs (10 N/m, 0.5 N s/m, rest length 3 m) to 1 m from six
    # anchors, two along each axis: each spring pushes across itself with k (1 - 3) = -20 N/m, so
    # omega^2 = (2 k - 4 (2 k)) / m = -60 1/s^2 along every axis. No mode has a frequency, yet the
    # model has stiffness, and the line does not say it has none.
    anchors = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
    squeezed = {"springmass": 1, "name": "squeezed", "gravity": [0, 0, 0],
                "particles": [{"name": "bob", "position": [0, 0, 0], "mass": 1}]
                + [{"name": f"a{i}", "position": list(p), "fixed": True} for i, p in enumerate(anchors)],
                "springs": [{"a": "bob", "b": f"a{i}", "stiffness": 10, "damping": 0.5, "rest_length": 3}
                            for i in range(6)]}
    path.write_text(json.dumps(squeezed))
    out = cli("modes", path).stdout
    rows = re.findall(r"^\s+\d+\s+\S+\s+(\S+)\s+(\S+)\s+\S+\s*$", out, re.M)
    assert [period for period, _ in rows] == 3 * ["unstable"]
    np.testing.assert_allclose([float(w2) for _, w2 in rows], [-60, -60, -60], rtol=1e-12)
    assert "no stiffness" not in summary_line(out, "explicit stability limit")


@pytest.mark.parametrize("ends", [("bob", "anchor"), ("anchor", "bob")])
def test_check_bound_of_a_bob_on_a_fixed_anchor(tmp_path, ends):
    # A held end adds no off-diagonal term to the Gershgorin row of the free end, whichever end
    # of the spring it is: a 2 kg bob on an 8 N/m spring at its rest length (no tension, so no
    # transverse stiffness) has the single axial frequency sqrt(8 / 2) = 2 rad/s, and the bound is
    # that exactly. Both are printed with 6 digits: compared to 1e-5.
    a, b = ends
    bob = {"springmass": 1, "name": "bob", "gravity": [0, 0, 0],
           "particles": [{"name": "anchor", "position": [0, 0, 0], "fixed": True},
                         {"name": "bob", "position": [0, 0, -1], "mass": 2}],
           "springs": [{"a": a, "b": b, "stiffness": 8, "rest_length": 1}]}
    path = tmp_path / "bob.json"
    path.write_text(json.dumps(bob))
    assert number_after(cli("check", path).stdout, "omega_max    <=") == pytest.approx(2.0, rel=1e-5)
    assert number_after(cli("modes", path, "-n", "0").stdout, "omega_max =") == pytest.approx(2.0, rel=1e-5)


def test_check_fastest_spring_goes_by_its_lighter_free_end(tmp_path):
    # The fastest spring is the largest sqrt(k / m) with m the lighter of its free ends (check's
    # usage): a 0.5 kg particle as end a of an 8 N/m spring to a 2 kg one gives sqrt(8 / 0.5) =
    # 4 rad/s, not the 2 rad/s of its end b; the same spring from a held anchor of 1e-6 kg to the
    # 2 kg particle gives 2 rad/s, the anchor's mass moving nothing. 6 digits printed.
    model = {"springmass": 1, "name": "fast", "gravity": [0, 0, 0],
             "particles": [{"name": "anchor", "position": [0, 0, 0], "fixed": True, "mass": 1e-6},
                           {"name": "light", "position": [1, 0, 0], "mass": 0.5},
                           {"name": "heavy", "position": [2, 0, 0], "mass": 2}],
             "springs": [{"a": "anchor", "b": "heavy", "stiffness": 8}, {"a": "light", "b": "heavy", "stiffness": 8}]}
    path = tmp_path / "fast.json"
    path.write_text(json.dumps(model))
    fastest = summary_line(cli("check", path).stdout, "fastest")
    assert number_after(fastest, "sqrt(k/m) =") == pytest.approx(4.0, rel=1e-5)
    assert "at spring 1, between light (particle 1) and heavy (particle 2)" in fastest


def test_check_warns_of_a_frequency_bound_that_overflows_beyond_each_spring(tmp_path):
    # A 1 kg bob between two held anchors on springs of 1e308 N/m: each spring's k / m is a double,
    # their sum at the bob, omega_max^2 = 2e308 1/s^2, is not. check warns that no integrator can
    # simulate the model and prints neither a bound nor a stable step.
    model = {"springmass": 1, "name": "over", "gravity": [0, 0, 0],
             "particles": [{"name": "left", "position": [0, 0, 0], "fixed": True},
                           {"name": "bob", "position": [1, 0, 0], "mass": 1},
                           {"name": "right", "position": [2, 0, 0], "fixed": True}],
             "springs": [{"a": "left", "b": "bob", "stiffness": 1e308}, {"a": "bob", "b": "right", "stiffness": 1e308}]}
    path = tmp_path / "over.json"
    path.write_text(json.dumps(model))
    out = cli("check", path).stdout
    assert number_after(summary_line(out, "fastest"), "sqrt(k/m) =") == pytest.approx(1e154, rel=1e-5)
    assert "no integrator can simulate the model" in summary_line(out, "warning")
    assert "omega_max" not in out and "explicit" not in out and out.rstrip().endswith("ok")


def oscillator_at_scale(path, length, time, mass):
    """The bundled damped oscillator (1 kg, 40 N/m, 0.4 N s/m, 0.5 m rest length, released 0.1 m
    out) in units of `length` [m], `time` [s] and `mass` [kg]: stiffness in mass / time^2, damping
    in mass / time."""
    path.write_text(json.dumps({
        "springmass": 1, "name": "scaled", "gravity": [0, 0, 0],
        "particles": [{"name": "anchor", "position": [0, 0, 0], "fixed": True},
                      {"name": "bob", "position": [0.6 * length, 0, 0], "mass": mass}],
        "springs": [{"a": "anchor", "b": "bob", "stiffness": 40.0 * mass / time**2,
                     "damping": 0.4 * mass / time, "rest_length": 0.5 * length}],
        "ports": [{"name": "tip", "particle": "bob", "kind": "probe"}],
        "simulation": {"stop_time": 5.0 * time, "output_interval": 0.01 * time}}))
    return path


@pytest.mark.parametrize("length, time, mass", [(1e-6, 1e-3, 1e-12), (1e-9, 1e-6, 1e-18)])
def test_tolerances_coarse_for_the_model_are_warned_about(tmp_path, length, time, mass):
    # A micromechanical oscillator: the bundled one with lengths of micrometres or nanometres and
    # a period of milliseconds or microseconds. Its amplitude, 0.1 length, and speeds, up to 0.6
    # length / time, lie near the default absolute tolerances (1e-8 m, 1e-6 m/s), which then hold
    # it to nothing: the closed form x = 0.5 + 0.1 e^(-g t) (cos(wd t) + g / wd sin(wd t)) (in
    # units of length and time; g = 0.2, wd^2 = 40 - g^2) is missed by over a tenth of the
    # amplitude. check and run say so. With both absolute tolerances scaled like the model (1e-8
    # length, 1e-6 length / time) the error is, in units of length, within a factor 2 of the
    # bundled oscillator's at its default tolerances (2.7e-5): below 1e-4 here, and no warning.
    model = oscillator_at_scale(tmp_path / "scaled.json", length, time, mass)
    g, wd = 0.2, math.sqrt(40.0 - 0.04)
    def error(*options):
        _, rows = run_csv(tmp_path, model, *options)
        t, x = rows[:, 0] / time, rows[:, 1] / length
        exact = 0.5 + 0.1 * np.exp(-g * t) * (np.cos(wd * t) + g / wd * np.sin(wd * t))
        return np.max(np.abs(x - exact))
    assert error() > 0.01
    assert re.search(r"^warning +the absolute tolerances, 1e-08 m and 1e-06 m/s, are coarse", cli("check", model).stdout, re.M)
    assert "springmass run: warning: the absolute tolerances" in cli("run", model, "-o", tmp_path / "x.csv").stderr
    if HAS_FMU:  # the FMU starts from the file's tolerances: packaging it warns too
        assert "springmass fmu: warning: the absolute tolerances" in cli("fmu", model, "-o", tmp_path / "x.fmu").stderr
    scaled = ["--atol-position", 1e-8 * length, "--atol-velocity", 1e-6 * length / time]
    assert error(*scaled) < 1e-4
    assert "warning" not in cli("run", model, "-o", tmp_path / "x.csv", *scaled).stderr
    # The bundled oscillator, and the same at a megahertz (micrometres and microseconds: speeds of
    # metres per second, which the default velocity tolerance holds), are warned about by nothing.
    for quiet in (MODELS / "oscillator.json", oscillator_at_scale(tmp_path / "mhz.json", 1e-6, 1e-6, 1e-12)):
        assert "warning" not in cli("check", quiet).stdout
        if HAS_FMU:
            assert "warning" not in cli("fmu", quiet, "-o", tmp_path / "quiet.fmu").stderr


def test_velocity_tolerances_below_the_round_off_of_a_stiff_spring_are_warned_about(tmp_path):
    # A 1 kg bob hanging at rest 1 m below a pivot on a critically damped 1e9 N/m rod. Its force
    # is known only to the rounding of the coordinates, 1e9 N/m x eps x 1 m, which moves the bob's
    # velocity by up to eps sqrt(1e9) / 2 = 3.5e-12 m/s in a step (simulation.h, sm_round_off).
    # Asked for a tenth of that or less, CVODE's steps fail over and over: at 1e-14 m/s
    # 20 000 steps do not reach 0.5 s, where 1e-10 m/s takes about a hundred (113 to 2 s).
    model = tmp_path / "rod.json"
    def write(atol_velocity):
        model.write_text(json.dumps({
            "springmass": 1, "name": "rod", "gravity": [0, 0, -9.81],
            "particles": [{"name": "pivot", "position": [0, 0, 0], "fixed": True},
                          {"name": "bob", "position": [0, 0, -1], "mass": 1}],
            "springs": [{"a": "pivot", "b": "bob", "stiffness": 1e9, "damping": 2 * math.sqrt(1e9), "rest_length": 1}],
            "simulation": {"stop_time": 0.5, "output_interval": 0.5, "atol_velocity": atol_velocity, "max_steps": 20000}}))
        return model
    warning = cli("check", write(1e-14)).stdout
    line = summary_line(warning, "warning")
    assert line.startswith("the absolute tolerance of velocities, 1e-14 m/s, is too tight for the "
                           "round-off of spring 0 (between pivot and bob), 1e+09 N/m")
    # printed to 2 digits
    noise = 2.220446049250313e-16 * math.sqrt(1e9) / 2
    assert number_after(line, "by up to") == pytest.approx(noise, rel=0.02)
    # with its unit, and the tolerance to use: a tenth of the noise
    assert f"by up to {noise:.2g} m/s in a step" in line, line
    assert line.endswith(f"(it may stop at max_steps; atol_velocity {0.1 * noise:.2g} m/s or more)"), line
    failed = cli("run", write(1e-14), "-o", tmp_path / "x.csv", status=1).stderr
    assert "springmass run: warning: the absolute tolerance of velocities, 1e-14 m/s, is too tight" in failed
    assert "CV_TOO_MUCH_WORK" in failed
    # -q prints errors only: the error, not the warning
    quiet = cli("run", write(1e-14), "-q", "-o", tmp_path / "x.csv", status=1).stderr
    assert "warning" not in quiet and "CV_TOO_MUCH_WORK" in quiet, quiet
    for sensible in (1e-10, 1e-6):
        assert "warning" not in cli("check", write(sensible)).stdout
        done = cli("run", write(sensible), "-o", tmp_path / "x.csv").stderr
        assert "warning" not in done and number_after(done, "solver dense:") < 1000
    # No bundled model asks for more than its round-off allows at its own settings.
    for bundled in sorted(MODELS.glob("*.json")):
        assert "too tight" not in cli("check", bundled).stdout, bundled


def test_check_warns_of_springs_that_start_broken(tmp_path):
    # A bob 1.2 m from its anchor on springs of rest length 1 m starts at strain 0.2: those with a
    # break strain of 0.2 or less break as the run starts (at t = 0; the first row, written before,
    # still has all six: elastic energy 6 x 10 (0.2)^2 / 2 = 1.2 J), the one of 0.3 does not. check names
    # the first three and counts the rest.
    strains = [0.1, 0.2, 0.3, 0.05, 0.15, 0.01]
    model = tmp_path / "prestretched.json"
    model.write_text(json.dumps({
        "springmass": 1, "name": "prestretched", "gravity": [0, 0, 0],
        "particles": [{"name": "anchor", "position": [0, 0, 0], "fixed": True},
                      {"name": "bob", "position": [1.2, 0, 0], "mass": 1}],
        "springs": [{"a": "anchor", "b": "bob", "stiffness": 10, "rest_length": 1, "break_strain": e}
                    for e in strains]}))
    warnings = [line for line in cli("check", model).stdout.splitlines() if line.startswith("warning")]
    assert warnings[0] == ("warning      spring 0, between anchor (particle 0) and bob (particle 1), starts at "
                           "strain 0.2, at or beyond its break strain 0.1: it breaks at t = 0")
    assert [int(w.split()[2].rstrip(",")) for w in warnings[:3]] == [0, 1, 3]
    assert warnings[3:] == ["warning      and 2 more springs start at or beyond their break strain"]
    run = cli("run", model, "--t-end", "0.1", "--output-interval", "0.1", "-o", tmp_path / "x.csv")
    assert sorted(int(s) for s in re.findall(r"^  spring (\d+) .* broke at t = 0 s$", run.stderr, re.M)) == [0, 1, 3, 4, 5]
    _, rows = run_csv(tmp_path, model, "--t-end", "0.1", "--output-interval", "0.1")
    assert rows[0, 2] == pytest.approx(6 * 10 * 0.2**2 / 2, rel=1e-12)
    # Then the spring of break strain 0.3 alone, which held 10 (0.2)^2 / 2 = 0.2 J at the start
    # and, without damping, holds at most that (to the tolerances of the run, far below 1e-6 J).
    assert 0 < rows[1, 2] < 0.2 + 1e-6
    assert "warning" not in cli("check", MODELS / "tearing_cloth.json").stdout


def test_check_warns_of_forces_that_overflow_at_the_start(tmp_path):
    # Files that break no rule but whose first evaluation overflows a double: run stops at t = 0,
    # check says so and names the particle. Weights of 10 kg x 1e308 m/s^2 = 1e309 N (two bobs, then
    # one); a damper of 1 N s/m closing at 1e200 m/s, whose force 1e200 N and acceleration are finite
    # but whose power kd r^2 = 1e400 W is not.
    def model(name, gravity, bobs, velocity=(0, 0, 0), damping=0):
        path = tmp_path / f"{name}.json"
        path.write_text(json.dumps({
            "springmass": 1, "name": name, "gravity": gravity,
            "particles": [{"name": "anchor", "position": [0, 0, 0], "fixed": True}] +
                         [{"name": f"bob{i}", "position": [1 + i, 0, 0], "mass": 10, "velocity": list(velocity)}
                          for i in range(bobs)],
            "springs": [{"a": "anchor", "b": f"bob{i}", "stiffness": 10, "damping": damping} for i in range(bobs)]}))
        return path

    def warnings(path):
        return [line for line in cli("check", path).stdout.splitlines() if line.startswith("warning")]

    assert warnings(model("heavy2", [0, 0, -1e308], 2)) == [
        "warning      the acceleration of bob0 (particle 1) (and of 1 more free particle) overflows at the "
        "initial state: springmass run stops at t = 0"]
    assert warnings(model("heavy3", [0, 0, -1e308], 3))[0].startswith(
        "warning      the acceleration of bob0 (particle 1) (and of 2 more free particles) overflows")
    hot = model("hot", [0, 0, 0], 1, velocity=(1e200, 0, 0), damping=1)
    assert warnings(hot) == ["warning      the dissipated power overflows at the initial state: springmass run "
                             "stops at t = 0"]
    # A run that stops at t = 0 asks nothing of its tolerances: no tight-tolerance warning beside
    # it, even at 1e-20 m/s, far below a tenth of the spring's round-off eps 1 m sqrt(10 / 10) / 2.
    hot_tight = tmp_path / "hot_tight.json"
    hot_tight.write_text(json.dumps(dict(json.loads(hot.read_text()), simulation={"atol_velocity": 1e-20})))
    assert warnings(hot_tight) == warnings(hot)
    # A finite force over a tiny mass: 10 N/m stretched 100 m pulls 1e-307 kg at 1e310 m/s^2.
    light = tmp_path / "light.json"
    light.write_text(json.dumps({
        "springmass": 1, "name": "light", "gravity": [0, 0, 0],
        "particles": [{"name": "anchor", "position": [0, 0, 0], "fixed": True},
                      {"name": "bob", "position": [101, 0, 0], "mass": 1e-307}],
        "springs": [{"a": "anchor", "b": "bob", "stiffness": 10, "rest_length": 1}]}))
    assert warnings(light) == ["warning      the acceleration of bob (particle 1) overflows at the initial state: "
                               "springmass run stops at t = 0"]
    # A fixed particle does not accelerate, whatever its weight (10 kg x 1e308 m/s^2).
    fixed = tmp_path / "fixed.json"
    fixed.write_text(json.dumps({
        "springmass": 1, "name": "fixed", "gravity": [0, 0, -1e308],
        "particles": [{"name": "anchor", "position": [0, 0, 0], "fixed": True, "mass": 10},
                      {"name": "bob", "position": [1, 0, 0], "mass": 1}],
        "springs": [{"a": "anchor", "b": "bob", "stiffness": 10}]}))
    assert warnings(fixed) == []
    for path in (model("heavy1", [0, 0, -1e308], 1), hot, light):
        run = cli("run", path, "--t-end", "0.1", "-o", tmp_path / "x.csv", status=1)
        assert "at t = 0 s" in run.stderr
    # The same files at ordinary scales warn of nothing.
    assert warnings(model("ordinary", [0, 0, -9.81], 3, velocity=(1, 0, 0), damping=1)) == []
    for bundled in sorted(MODELS.glob("*.json")):
        assert "overflows" not in cli("check", bundled).stdout


def test_check_counts_one_spring_in_the_singular(tmp_path):
    # Four springs of rest length 1 m from an anchor to a bob 1.2 m away (strain 0.2), each with a
    # break strain of 0.1: check names three of them and counts the fourth, one spring. A rope of
    # one segment is listed with one segment and one spring.
    model = tmp_path / "four.json"
    model.write_text(json.dumps({
        "springmass": 1, "name": "four", "gravity": [0, 0, 0],
        "particles": [{"name": "anchor", "position": [0, 0, 0], "fixed": True},
                      {"name": "bob", "position": [1.2, 0, 0], "mass": 1}],
        "springs": [{"a": "anchor", "b": "bob", "stiffness": 10, "rest_length": 1, "break_strain": 0.1}] * 4,
        "structures": [{"type": "rope", "name": "short", "start": [0, 1, 0], "end": [1, 1, 0], "segments": 1,
                        "structural": {"stiffness": 10}}]}))
    out = cli("check", model).stdout
    warnings = [line for line in out.splitlines() if line.startswith("warning")]
    assert len(warnings) == 4
    assert warnings[3] == "warning      and 1 more spring starts at or beyond its break strain"
    assert "short        rope of 1 segment: particles 2 - 3, 1 spring (1 structural)" in out


def test_check_notes_springs_of_the_file_on_a_pair_another_spring_joins(tmp_path):
    # A rope of three segments (springs 0, 2, 4 structural, 1 and 3 bending, in the order of their
    # first particle) and the file's springs 5 - 9: spring 5 on the rope's segment 1 - 2, spring 6
    # between the two bobs, spring 7 again between them (listed twice, the ends swapped), spring 8
    # alone on its pair, spring 9 on the bobs a third time. Noted: 5 (with the rope's 2), 7 and 9
    # (with 6); not 8, nor the rope's own springs. A mesh whose bending springs share a pair by
    # design (the bundled flag: 14 such springs) has no note.
    model = tmp_path / "twice.json"
    spring = {"stiffness": 10}
    model.write_text(json.dumps({
        "springmass": 1, "name": "twice",
        "particles": [{"name": "b1", "position": [0, 0, -1], "mass": 1},
                      {"name": "b2", "position": [0, 0, -2], "mass": 1}],
        "structures": [{"type": "rope", "name": "r", "start": [0, 0, 0], "end": [3, 0, 0], "segments": 3,
                        "structural": {"stiffness": 100}, "bending": {"stiffness": 1}}],
        "fixed": ["r[0]"],
        "springs": [dict(spring, a="r[2]", b="r[1]"), dict(spring, a="b1", b="b2"), dict(spring, a="b2", b="b1"),
                    dict(spring, a="r[3]", b="b1"), dict(spring, a="b1", b="b2")]}))
    notes = [line for line in cli("check", model).stdout.splitlines() if line.startswith("note")]
    parallel = ": they act in parallel, their forces add (a spring listed twice?)"
    # In the order of the particles they join.
    assert notes == ["note         springs 6 and 7 both join b1 (particle 0) and b2 (particle 1)" + parallel,
                     "note         springs 6 and 9 both join b1 (particle 0) and b2 (particle 1)" + parallel,
                     "note         springs 2 and 5 both join r[1] (particle 3) and r[2] (particle 4)" + parallel]
    # Beyond three, the rest are counted, in the singular for one.
    text = json.loads(model.read_text())
    for more, counted in ((1, "and 1 more spring joins"), (2, "and 2 more springs join")):
        model.write_text(json.dumps(dict(text, springs=text["springs"] + [dict(spring, a="b1", b="b2")] * more)))
        notes = [line for line in cli("check", model).stdout.splitlines() if line.startswith("note")]
        assert notes[3:] == [f"note         {counted} the same particles as an earlier one"]
    assert not [line for line in cli("check", MODELS / "flag.json").stdout.splitlines() if line.startswith("note")]


def test_check_summarises_the_model(tmp_path):
    out = cli("check", MODELS / "two_mass_chain.json").stdout
    assert summary_line(out, "particles") == "3: 2 free, 1 fixed"
    assert summary_line(out, "held") == "base (particle 0)"
    assert summary_line(out, "springs").startswith("2: 2 rest-length, 0 zero-length")
    assert summary_line(out, "total mass") == "2.5 kg"
    assert summary_line(out, "base").split()[0] == "motion"
    assert summary_line(out, "m1").split()[0] == "probe"
    assert summary_line(out, "m2").split()[0] == "force"
    # The stiffest spring, and the fastest single spring-mass pair sqrt(k / m) with the lighter
    # mass (k2 = 25 N/m on m2 = 0.5 kg: 7.07107 rad/s, 1.1254 Hz; 2 / omega = 0.283 s).
    assert summary_line(out, "stiffest").startswith("spring 0, 40 N/m")
    fastest = summary_line(out, "fastest")
    omega = math.sqrt(25 / 0.5)
    assert number_after(fastest, "sqrt(k/m) =") == pytest.approx(omega, rel=1e-5)
    assert number_after(fastest, "rad/s (") == pytest.approx(omega / (2 * math.pi), rel=1e-4)
    # The bound on the highest frequency: the largest mass-scaled Gershgorin row sum of the
    # springs' scalar Laplacian (both springs within their rest length or barely stretched, so
    # each counts with its ks): m1's row 40/1 + 25 (1/1 + 1/sqrt(0.5)), m2's 25/0.5 + 25/sqrt(0.5).
    # It must lie above the exact omega_max, the axial mode of the chain (transverse stiffness is
    # only the springs' tension), from the 2 x 2 eigenproblem; 6 digits printed.
    bound = math.sqrt(max(40 + 25 * (1 + 1 / math.sqrt(0.5)), 25 / 0.5 + 25 / math.sqrt(0.5)))
    assert number_after(out, "omega_max    <=") == pytest.approx(bound, rel=1e-5)
    axial = np.array([[65.0, -25 / math.sqrt(0.5)], [-25 / math.sqrt(0.5), 50.0]])
    exact = math.sqrt(np.linalg.eigvalsh(axial).max())
    assert exact == pytest.approx(9.67688383, rel=1e-8)  # springmass modes' omega_max
    assert bound >= exact
    # The damping rate's bound, as the stiffness's with d1 = d2 = 0.2 N s/m, and the explicit step
    # symplectic Euler takes with both (3 digits printed).
    gamma = max(0.2 + 0.2 * (1 + 1 / math.sqrt(0.5)), 0.2 / 0.5 + 0.2 / math.sqrt(0.5))
    step = 2 / (gamma / 2 + math.sqrt(gamma**2 / 4 + bound**2))
    assert number_after(out, "steps up to at least") == pytest.approx(step, rel=2e-3)
    assert out.rstrip().endswith("ok")
    # The file's settings (stop time 5 s, output interval 0.01 s; rtol and solver their defaults)
    # and its gravity and mass damping.
    assert summary_line(out, "simulation") == "stop time 5 s, output interval 0.01 s, rtol 1e-06, solver auto"
    # A file that keeps CVODE's history where inputs jump says so.
    keep = json.loads((MODELS / "two_mass_chain.json").read_text())
    keep["simulation"]["input_changes"] = "keep"
    (tmp_path / "keep.json").write_text(json.dumps(keep))
    assert summary_line(cli("check", tmp_path / "keep.json").stdout, "simulation") == \
        "stop time 5 s, output interval 0.01 s, rtol 1e-06, solver auto, history kept where inputs jump"
    # So does one that switches BDF's stability limit detection off.
    keep["simulation"]["stability_limit_detection"] = False
    (tmp_path / "keep.json").write_text(json.dumps(keep))
    assert summary_line(cli("check", tmp_path / "keep.json").stdout, "simulation") == \
        "stop time 5 s, output interval 0.01 s, rtol 1e-06, solver auto, history kept where inputs jump, " \
        "stability limit detection off"
    # Adams has no such detection: with its method the setting goes unnamed.
    keep["simulation"]["method"] = "adams"
    (tmp_path / "keep.json").write_text(json.dumps(keep))
    assert summary_line(cli("check", tmp_path / "keep.json").stdout, "simulation") == \
        "stop time 5 s, output interval 0.01 s, rtol 1e-06, method adams (fixed point, no linear solver), " \
        "history kept where inputs jump"
    assert summary_line(out, "gravity") == "(0, 0, 0) m/s^2, mass damping 0 1/s"
    rope = cli("check", MODELS / "hanging_rope.json").stdout
    assert summary_line(rope, "gravity") == "(0, 0, -9.81) m/s^2, mass damping 0.1 1/s"
    assert "rope of 20 segments: particles 0 - 20, 20 springs (20 structural)" in rope
    assert summary_line(rope, "particles") == "21: 20 free, 1 fixed"
    # --set as for the other commands: n = 40 segments, the probes at rope[40] and rope[20]; a
    # value the file cannot take is its error, exit 1.
    rope = cli("check", MODELS / "hanging_rope.json", "--set", "n=40").stdout
    assert summary_line(rope, "particles") == "41: 40 free, 1 fixed"
    assert summary_line(rope, "tip") == "probe  at rope[40] (particle 40)"
    assert summary_line(rope, "middle") == "probe  at rope[20] (particle 20)"
    err = cli("check", MODELS / "hanging_rope.json", "--set", "n=0", status=1).stderr
    assert "--set n=0" in err and "segments" in err


def test_check_names_no_linear_solver_for_adams(tmp_path):
    # A file that asks for Adams names a linear solver all the same (or keeps the default "auto");
    # Adams' fixed-point iteration uses none, as springmass run's summary says: check must not
    # report one as the solver the run uses.
    model = json.loads((MODELS / "oscillator.json").read_text())
    model["simulation"].update(method="adams", solver="klu")
    path = tmp_path / "adams.json"
    path.write_text(json.dumps(model))
    line = summary_line(cli("check", path).stdout, "simulation")
    assert line == "stop time 5 s, output interval 0.01 s, rtol 1e-08, method adams (fixed point, no linear solver)"
    assert "Adams (fixed point, no linear solver)" in cli("run", path, "-o", tmp_path / "adams.csv", "--t-end", 0.1).stderr
    # BDF keeps the solver it names.
    model["simulation"].update(method="bdf")
    path.write_text(json.dumps(model))
    assert summary_line(cli("check", path).stdout, "simulation").endswith("rtol 1e-08, solver klu")


def test_check_sheet_grid_and_the_row_limit(tmp_path):
    # A sheet of nu = 3 by nv = 5 points is summarised in the file's order, 3 x 5, its 15 particles
    # numbered from 0. `springmass run` writes at most 1e9 rows (docs/model-format.md): a stop time
    # of exactly 1e9 output intervals is taken, one interval more is refused.
    sheet = {"springmass": 1, "name": "sheet", "structures": [
        {"type": "sheet", "name": "s", "origin": [0, 0, 0], "edge_u": [1, 0, 0], "edge_v": [0, 1, 0],
         "nu": 3, "nv": 5, "mass": 1, "structural": {"strain_stiffness": 10}}],
        "simulation": {"stop_time": 1e9, "output_interval": 1}}
    path = tmp_path / "sheet.json"
    path.write_text(json.dumps(sheet))
    out = cli("check", path).stdout
    assert summary_line(out, "s").startswith("sheet 3 x 5: particles 0 - 14, "), out
    sheet["simulation"]["stop_time"] = 1e9 + 1
    path.write_text(json.dumps(sheet))
    assert "would make more than 1e+09 output rows" in cli("check", path, status=1).stderr


# --- fmu ---------------------------------------------------------------------------------------

@pytest.mark.skipif(not HAS_FMU, reason="a build without the FMU runtime")
def test_fmu_carries_the_reference_and_the_values_set(tmp_path):
    # The reference as fmpy's write_csv writes a result of the FMU: quoted names, its own number
    # format. (A result made here, not by simulate_fmu: in an instrumented build the FMU cannot be
    # loaded into this interpreter, which has no sanitizer runtime preloaded.)
    from fmpy.util import write_csv
    reference = tmp_path / "reference.csv"
    result = np.array([(0.0, 0.0, 0.5, 100000), (0.05, -0.012, 0.5, 100000)],
                      dtype=[("time", np.float64), ("tip.z", np.float64), ("middle.x", np.float64),
                             ("solver.max_steps", np.int32)])
    write_csv(reference, result)
    assert reference.read_text().startswith('"time","tip.z","middle.x","solver.max_steps"\n0.0,0.0,0.5,100000\n')
    fmu = tmp_path / "rope.fmu"
    out = cli("fmu", MODELS / "hanging_rope.json", "-o", fmu, "--reference", reference, "--set", "E=150").stdout
    assert "E=150" in out
    with zipfile.ZipFile(fmu) as z:
        assert z.read("resources/reference.csv") == reference.read_bytes()
        assert "E=150" in z.read("resources/parameters.txt").decode()


@pytest.mark.skipif(not HAS_FMU, reason="a build without the FMU runtime")
@pytest.mark.parametrize("text, message", [
    ("", "1:1: an empty file"),
    ("t,tip.x\n0,1\n", '1:1: the first column is "t", not "time"'),
    ('"time",tip.x,"tip.q"\n0,1,2\n', '1:14: "tip.q" is not a variable of the FMU'),
    ("time,solver.method\n0,1\n", '1:6: "solver.method" is a String variable: a result holds numbers'),
    ("time,tip.x,tip.y,tip.x\n0,1,2,3\n", '1:18: "tip.x" is named twice'),
    ("time,tip.x\n0,1\n0.5,nan\n", '3:5: "nan" is not a finite decimal number'),
    ("time,tip.x\n0,1\n0.5, 2\n", '3:5: " 2" is not a finite decimal number'),
    ("time,tip.x\n0,0x1p3\n", '2:3: "0x1p3" is not a finite decimal number'),
    ("time,tip.x\n0,1e400\n", '2:3: "1e400" is not a finite decimal number'),
    ("time,tip.x\n0,1.\n0.5,.\n", '3:5: "." is not a finite decimal number'),
    ("time,tip.x\n0,2e\n", '2:3: "2e" is not a finite decimal number'),
    ('time,tip.x\n0,"1"\n', '2:3: "1" is quoted: a result writes its numbers without quotes'),
    ("time,solver.max_steps\n0,1.5\n", '2:3: solver.max_steps is an Integer variable: "1.5" is no such value'),
    ("time,solver.max_steps\n0,2147483648\n",
     '2:3: solver.max_steps is an Integer variable: "2147483648" is no such value'),
    ("time,solver.max_steps\n0,-2147483649\n",
     '2:3: solver.max_steps is an Integer variable: "-2147483649" is no such value'),
    # A Boolean variable holds false and true as 0 and 1 (fmpy's read_csv reads no True or False).
    ("time,solver.stability_limit_detection\n0,2\n",
     '2:3: solver.stability_limit_detection is a Boolean variable: "2" is neither 0 nor 1'),
    ("time,solver.stability_limit_detection\n0,1\n0.5,-1\n",
     '3:5: solver.stability_limit_detection is a Boolean variable: "-1" is neither 0 nor 1'),
    ("time,solver.stability_limit_detection\n0,0.5\n",
     '2:3: solver.stability_limit_detection is a Boolean variable: "0.5" is neither 0 nor 1'),
    ("time,solver.stability_limit_detection\n0,True\n", '2:3: "True" is not a finite decimal number'),
    ("\ufefftime,tip.x\n0,1\n", "1:1: a byte-order mark before the header: write the file without one"),
    ("time,tip.x\r0,1\n", "1:11: a carriage return without a line feed: lines end in LF or CRLF"),
    ("time,tip.x\r\n0,1\r\n0.5\r\n", "3:4: fewer fields than columns: the header names 2 columns"),
    ("time,tip.x\n0,1,\n", "2:4: more fields than columns: the header names 2 columns"),
    ("time,tip.x\n1,1\n0.5,1\n", "3:1: time 0.5 s is before the previous row's 1 s"),
    ("time,tip.x\n0,1\n\n1,1\n", "3:1: an empty line: a result has none"),
    ("time,tip.x\n0,1\n\n", "3:1: an empty line: a result has none"),
    ('time,"tip.x\n0,1\n', "1:6: a quoted field is not closed"),
    ('time,"tip.x"y\n0,1\n', "1:13: text after the closing quote of a field"),
    # A doubled quote in a quoted field is one quote of it (RFC 4180); a quoted field's line ends
    # are lines of the file, counted in the places after it.
    ('time,"tip"".x"\n0,1\n', '1:6: "tip".x" is not a variable of the FMU'),
    ('time,tip.x\n0,1\n0.5,"2\n"x\n', "4:2: text after the closing quote of a field"),
    ('time,"tip\n.q"\n0,1\n', '1:6: "tip\\u000a.q" is not a variable of the FMU'),
    ('time,tip.x\n0,"1\n2"\n', '2:3: "1\\u000a2" is quoted: a result writes its numbers without quotes'),
    ("time,tip.x\n", "2:1: no rows after the header"),
    ("time,tip.x\n0,\x00\n", "2:3: a NUL byte: not a text file"),
    ('time,"a\x1b[2Jb"\n0,1\n', '1:6: "a\\u001b[2Jb" is not a variable of the FMU'),
    # A field longer than a message shows is cut at a character, and says so.
    ("time," + "x" * 59 + "\u00e9y\n0,1\n", '1:6: "' + "x" * 59 + '"... is not a variable of the FMU'),
    ("time,tip.x\n0," + "1" * 60 + "x\n", '2:3: "' + "1" * 60 + '"... is not a finite decimal number'),
])
def test_fmu_refuses_a_reference_that_is_no_result_of_it(tmp_path, text, message):
    # Before anything is written: no FMU, and the last good one at the place stays.
    reference = tmp_path / "reference.csv"
    reference.write_bytes(text.encode())
    fmu = tmp_path / "rope.fmu"
    fmu.write_bytes(b"an earlier FMU")
    err = cli("fmu", MODELS / "hanging_rope.json", "-o", fmu, "--reference", reference, status=1).stderr
    assert err == f"springmass fmu: --reference {reference}:{message}\n"
    assert fmu.read_bytes() == b"an earlier FMU"


@pytest.mark.skipif(not HAS_FMU, reason="a build without the FMU runtime")
def test_fmu_takes_a_reference_with_events_and_without_a_last_line_end(tmp_path):
    # A time repeated at an event, CRLF line ends, names quoted or not, numbers in every form a
    # decimal takes, whole numbers of an Integer variable (down to -2^31 and up to 2^31 - 1, its
    # 32 bits), 0 and 1 for a Boolean one, and no line end after the last row.
    reference = tmp_path / "reference.csv"
    text = (b'"time",tip.x,"energy.kinetic",solver.max_steps,solver.stability_limit_detection\r\n'
            b'0,1,0,7,1\r\n0.5,1e-3,-2.5E+2,+8.0,0\r\n0.5,.5,3,-9e2,1.0\r\n0.75,1,1,-2147483648,0\r\n'
            b'0.75,1,1,2147483647,-0\r\n1,2.,+3,10,1e0')
    for ending in (b"", b"\n", b"\r\n"):
        reference.write_bytes(text + ending)
        fmu = tmp_path / "rope.fmu"
        cli("fmu", MODELS / "hanging_rope.json", "-o", fmu, "--reference", reference)
        with zipfile.ZipFile(fmu) as z:
            assert z.read("resources/reference.csv") == text + ending


@pytest.mark.skipif(not HAS_FMU or SANITIZED, reason="a build without the FMU runtime; a sanitizer's shadow memory")
def test_fmu_checks_a_reference_without_keeping_its_numbers(tmp_path):
    # The check reads the numbers and keeps none: the peak memory of packing a 40 MB reference of
    # one-digit numbers is the text and the archive's work, not 8 bytes per number on top (four
    # times the text, and up to twice that while the array doubles: 200 MB in all for 40 MB,
    # measured, against 53 MB).
    reference = tmp_path / "reference.csv"
    names = ["time", "tip.x", "tip.y", "tip.z", "tip.vx", "tip.vy", "tip.vz", "energy.kinetic"]
    reference.write_text(",".join(names) + "\n" + ("0," * (len(names) - 1) + "0\n") * 2_500_000)
    measure = ("import resource, subprocess, sys; subprocess.run(sys.argv[1:], check=True, stdout=subprocess.DEVNULL); "
               "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)")  # [KiB]
    peak = subprocess.run([sys.executable, "-c", measure, str(CLI), "fmu", str(MODELS / "oscillator.json"), "-o",
                           str(tmp_path / "osc.fmu"), "--reference", str(reference)],
                          capture_output=True, text=True, check=True).stdout
    assert int(peak) * 1024 < 2 * reference.stat().st_size + 64e6, (int(peak), reference.stat().st_size)


@pytest.mark.skipif(not HAS_FMU, reason="a build without the FMU runtime")
def test_fmu_values_set_are_those_the_fmu_starts_from(tmp_path):
    # --set z=0 on a file's -0 is a value of its own, as editing the file to 0 is (a velocity of
    # 0 where the file's starts at -0; sm_document_set_parameter takes it), and so is -0 on a
    # file's 0: both go into resources/parameters.txt, beside a value that changes more; every
    # line there is a start value of the FMU. A value the file has, to the sign of a zero, is not.
    model = json.loads((MODELS / "oscillator.json").read_text())
    model["parameters"]["z"] = -0.0
    model["parameters"]["w"] = 0.0
    model["gravity"] = ["w", "z", 0]
    path = tmp_path / "zero.json"
    path.write_text(json.dumps(model))
    runtime = stand_in_runtime(tmp_path / "runtime", "binary")
    fmu = tmp_path / "zero.fmu"
    cli("fmu", path, "-o", fmu, "--runtime", runtime, "--set", "z=0", "--set", "w=-0.0", "--set", "k=80")
    with zipfile.ZipFile(fmu) as z:
        lines = z.read("resources/parameters.txt").decode().split()
        variables = ET.fromstring(z.read("modelDescription.xml")).iter("ScalarVariable")
        starts = {v.get("name"): v[0].get("start") for v in variables}
    assert lines == ["k=80", "z=0", "w=-0"]
    assert all(starts[name] == value for name, value in (line.split("=") for line in lines))
    same = tmp_path / "same.fmu"
    cli("fmu", path, "-o", same, "--runtime", runtime, "--set", "z=-0.0", "--set", "w=0")
    with zipfile.ZipFile(same) as z:
        assert "resources/parameters.txt" not in z.namelist()


@pytest.mark.skipif(not HAS_FMU, reason="a build without the FMU runtime")
def test_fmu_of_a_mesh_read_from_an_obj_file_runs_without_the_file(tmp_path):
    # docs/model-format.md: a mesh's "file" is found beside the model file, wherever the tool runs;
    # the FMU packs the model with the mesh's vertices and triangles inline (the OBJ file's numbers,
    # its scale and origin kept as the file gives them), so that it runs where the OBJ file is not,
    # with the same model and the same parameters.
    (tmp_path / "meshes").mkdir()
    obj = tmp_path / "meshes" / "flag.obj"
    # A 3 x 3 grid of vertices 500 mm apart, in the x-z plane, as four quads.
    vertices = [(500 * j, 0, 500 * i) for i in range(3) for j in range(3)]
    obj.write_text("# in millimetres\n" + "".join(f"v {x} {y} {z}\n" for x, y, z in vertices) +
                   "vn 0 1 0\nf 1//1 2//1 5//1 4//1\nf 2//1 3//1 6//1 5//1\nf 4 5 8 7\nf 5 6 9 8\n")
    model = {"springmass": 1, "name": "obj_flag", "parameters": {"s": 0.001, "E": 400.0},
             "structures": [{"type": "mesh", "name": "flag", "file": "meshes/flag.obj", "scale": "s",
                             "origin": [0, 0, 1], "density": 0.5, "edge": {"strain_stiffness": "E"}}],
             "fixed": ["flag[0]", "flag[3]", "flag[6]"],
             "ports": [{"name": "tip", "particle": "flag[8]", "kind": "probe"}]}
    path = tmp_path / "flag.json"
    path.write_text(json.dumps(model))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    summary = cli("check", path, cwd=elsewhere).stdout
    # 16 edges (12 on the grid's lines, a diagonal in each quad), each once.
    assert "mesh of 9 vertices from meshes/flag.obj: particles 0 - 8, 16 springs (16 edge)" in summary
    fmu = tmp_path / "flag.fmu"
    cli("fmu", path, "-o", fmu, cwd=elsewhere)
    obj.unlink()
    with zipfile.ZipFile(fmu) as z:
        packed = json.loads(z.read("resources/model.json"))
    mesh = packed["structures"][0]
    assert "file" not in mesh and mesh["scale"] == "s" and mesh["origin"] == [0, 0, 1]
    assert mesh["vertices"] == [list(v) for v in vertices]
    assert mesh["triangles"] == [[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4], [3, 4, 7], [3, 7, 6], [4, 5, 8],
                                 [4, 8, 7]]
    assert packed["parameters"] == model["parameters"] and packed["ports"] == model["ports"]
    unpacked = tmp_path / "unpacked.json"
    unpacked.write_text(json.dumps(packed))
    # The same model: every line of the summary but the structure's, which no longer names the file.
    again = cli("check", unpacked).stdout
    assert again.replace("mesh of 9 vertices:", "mesh of 9 vertices from meshes/flag.obj:") == summary
    if not SANITIZED:
        from fmpy import simulate_fmu
        result = simulate_fmu(str(fmu), stop_time=0.01, output_interval=0.01, output=["tip.x", "tip.z"])
        # The free corner starts at origin + s (1000, 0, 1000) mm, exactly (1 + 1 rounds to 2).
        assert (result["tip.x"][0], result["tip.z"][0]) == (1.0, 2.0)


@pytest.mark.parametrize("command, option", [("run", "-o"), ("statics", "-o"), ("statics", "--save-model"),
                                             ("modes", "-o"),
                                             pytest.param("fmu", "-o", marks=pytest.mark.skipif(
                                                 not HAS_FMU, reason="a build without the FMU runtime"))])
def test_no_output_overwrites_the_obj_file_a_mesh_reads(command, option, tmp_path):
    # An OBJ file the model's meshes read is an input like the model file: an output named as it
    # (here under another name for it, from another folder) is a usage error, and the file is kept.
    (tmp_path / "meshes").mkdir()
    obj = tmp_path / "meshes" / "sail.obj"
    text = "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nf 1 2 3 4\n"
    obj.write_text(text)
    model = tmp_path / "sail.json"
    model.write_text(json.dumps({"springmass": 1, "name": "sail", "fixed": ["sail[0]", "sail[1]"],
                                 "structures": [{"type": "mesh", "name": "sail", "file": "meshes/sail.obj",
                                                 "edge": {"stiffness": 100}}]}))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    runtime = ["--runtime", stand_in_runtime(tmp_path / "runtime", "binary")] if command == "fmu" else []
    output = "../meshes/./sail.obj"
    out = cli(command, "../sail.json", option, output, *runtime, status=2, cwd=elsewhere)
    assert out.stderr == (f"springmass {command}: {option} {output} would overwrite the OBJ file of the mesh sail "
                          "(structures[0].file), which it reads; give another name\n")
    assert obj.read_text() == text


def test_check_warns_of_a_mesh_cut_at_a_seam_of_duplicated_vertices(tmp_path):
    # Two quads side by side whose common edge is written twice, as a modeller exports a seam: the
    # mesh is two pieces that fall apart, and check says where (the vertices at (1, 0, 0) and
    # (1, 0, 1) m). Merged, or stitched by springs of the file's own, it is one piece: no warning.
    seam = "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nv 1 0 0\nv 2 0 0\nv 2 0 1\nv 1 0 1\nf 1 2 3 4\nf 5 6 7 8\n"
    merged = "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nv 2 0 0\nv 2 0 1\nf 1 2 3 4\nf 2 5 6 3\n"
    stitches = [{"a": "strip[4]", "b": "strip[1]", "kind": "zero_length", "stiffness": 1000},
                {"a": "strip[2]", "b": "strip[7]", "kind": "zero_length", "stiffness": 1000}]
    warned = []
    for name, obj, springs in (("seam", seam, []), ("merged", merged, []), ("stitched", seam, stitches)):
        (tmp_path / f"{name}.obj").write_text(obj)
        model = tmp_path / f"{name}.json"
        model.write_text(json.dumps({"springmass": 1, "name": name, "fixed": ["strip[0]", "strip[3]"],
                                     "structures": [{"type": "mesh", "name": "strip", "file": f"{name}.obj",
                                                     "edge": {"stiffness": 100}}], "springs": springs}))
        warned.append([line for line in cli("check", model).stdout.splitlines() if line.startswith("warning")])
    cut = ("start at the same position, ({}) m, and no spring joins them: the mesh strip is cut there (a seam of "
           "duplicated vertices? merge them in the modeller)")
    assert warned[0] == ["warning      strip[1] (particle 1) and strip[4] (particle 4) " + cut.format("1, 0, 0"),
                         "warning      strip[2] (particle 2) and strip[7] (particle 7) " + cut.format("1, 0, 1")]
    assert warned[1] == [] and warned[2] == []


def test_check_takes_copies_of_a_vertex_stitched_through_one_of_them_for_one_piece(tmp_path):
    # Three triangles meeting at the origin, each with its own copy of the corner there (a pole as
    # modellers export one, pole[0], pole[3] and pole[6]). Stitched to pole[0] both, the copies are
    # one piece, though no spring joins pole[3] and pole[6] directly: no warning. Stitched only
    # pole[0] to pole[3], pole[6] is loose: the mesh is cut there.
    obj = tmp_path / "pole.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 0\nv -1 0 0\nv 0 -1 0\nv 0 0 0\nv 1 -1 0\nv 1 -2 0\n"
                   "f 1 2 3\nf 4 5 6\nf 7 8 9\n")

    def stitch(a, b):
        return {"a": f"pole[{a}]", "b": f"pole[{b}]", "kind": "zero_length", "stiffness": 1000}

    warned = []
    for name, springs in (("star", [stitch(0, 3), stitch(0, 6)]), ("loose", [stitch(0, 3)])):
        model = tmp_path / f"{name}.json"
        model.write_text(json.dumps({"springmass": 1, "name": name, "fixed": ["pole[1]"],
                                     "structures": [{"type": "mesh", "name": "pole", "file": "pole.obj",
                                                     "edge": {"stiffness": 100}}], "springs": springs}))
        warned.append([line for line in cli("check", model).stdout.splitlines() if line.startswith("warning")])
    assert warned[0] == []
    assert warned[1] == ["warning      pole[3] (particle 3) and pole[6] (particle 6) start at the same position, "
                         "(0, 0, 0) m, and no spring joins them: the mesh pole is cut there (a seam of "
                         "duplicated vertices? merge them in the modeller)"]


def stand_in_runtime(folder, binary):
    """A runtime folder as `springmass fmu --runtime` takes it, with stand-ins for the FMU binary
    (its text `binary`, executable as a built one is), a library and a licence, which keep the
    archives small."""
    (folder / "binaries" / "linux64").mkdir(parents=True)
    (folder / "binaries" / "linux64" / "springmass_fmu.so").write_text(binary)
    (folder / "binaries" / "linux64" / "springmass_fmu.so").chmod(0o755)
    (folder / "binaries" / "linux64" / "libextra.so.1").write_text("library")
    (folder / "documentation" / "licenses").mkdir(parents=True)
    (folder / "documentation" / "licenses" / "license.txt").write_text("licences")
    return folder


@pytest.mark.skipif(not HAS_FMU, reason="a build without the FMU runtime")
def test_fmu_packs_the_runtime_it_is_given(tmp_path):
    # docs/fmu.md: the runtime comes from --runtime, else from $SPRINGMASS_FMU_RUNTIME; the FMU
    # holds the binary under the model's name, the libraries and licences as they are, and the
    # model file byte for byte. The staging folder goes into $TMPDIR and is removed again.
    osc = MODELS / "oscillator.json"
    given = stand_in_runtime(tmp_path / "given", "given binary")
    from_environment = stand_in_runtime(tmp_path / "environment", "binary of the environment")
    staging = tmp_path / "staging"
    staging.mkdir()
    env = dict(os.environ, SPRINGMASS_FMU_RUNTIME=str(from_environment), TMPDIR=str(staging))
    for options, binary in ((["--runtime", given], "given binary"), ([], "binary of the environment")):
        fmu = tmp_path / "oscillator.fmu"
        cli("fmu", osc, "--output", fmu, *options, env=env)
        with zipfile.ZipFile(fmu) as z:
            names = set(z.namelist())
            assert z.read("binaries/linux64/oscillator.so") == binary.encode()
            assert z.read("binaries/linux64/libextra.so.1") == b"library"
            assert z.read("documentation/licenses/license.txt") == b"licences"
            assert z.read("resources/model.json") == osc.read_bytes()
            # The binary keeps its mode (rwxr-xr-x), as the runtime's files are copied with theirs.
            assert z.getinfo("binaries/linux64/oscillator.so").external_attr >> 16 & 0o777 == 0o755
        assert "binaries/linux64/springmass_fmu.so" not in names and "resources/parameters.txt" not in names
        assert "resources/reference.csv" not in names
        fmu.unlink()
    assert list(staging.iterdir()) == []


def signalling_zip(tools, name):
    """A folder `tools` holding a zip that sends the signal `name` (INT, TERM, HUP, ...) to the
    process that runs it, then makes the archive with the real zip; put it first on PATH."""
    tools.mkdir()
    real_zip = shutil.which("zip")
    assert real_zip is not None
    (tools / "zip").write_text(f'#!/bin/sh\nkill -{name} $PPID\nexec "{real_zip}" "$@"\n')
    (tools / "zip").chmod(0o755)
    return tools


@pytest.mark.skipif(not HAS_FMU, reason="a build without the FMU runtime")
@pytest.mark.parametrize("name, text", [("TERM", "Terminated"), ("INT", "Interrupt"), ("HUP", "Hangup")])
def test_fmu_stopped_by_a_signal_leaves_nothing_behind(tmp_path, name, text):
    # A packaging stopped while zip runs (a kill, Ctrl-C, which zip gets too, or the terminal
    # closed) removes its staging folder, a copy of the whole runtime, leaves an earlier FMU at the
    # output as it was and ends with the signal's status. The zip here stands in for one that is
    # still working when the tool is stopped: it sends the signal to the tool, then finishes the
    # archive.
    runtime = stand_in_runtime(tmp_path / "runtime", "binary")
    staging = tmp_path / "staging"
    staging.mkdir()
    tools = signalling_zip(tmp_path / "tools", name)
    fmu = tmp_path / "oscillator.fmu"
    fmu.write_bytes(b"an earlier FMU")
    env = dict(os.environ, TMPDIR=str(staging), PATH=f"{tools}:{os.environ['PATH']}")
    status = -signal.Signals["SIG" + name].value
    out = cli("fmu", MODELS / "oscillator.json", "-o", fmu, "--runtime", runtime, status=status, env=env)
    assert list(staging.iterdir()) == []
    assert fmu.read_bytes() == b"an earlier FMU"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["oscillator.fmu", "runtime", "staging", "tools"]
    assert out.stderr.endswith(f"springmass fmu: stopped by {text}; {fmu} not written\n"), out.stderr


@pytest.mark.skipif(not HAS_FMU, reason="a build without the FMU runtime")
def test_fmu_into_a_pipe_without_a_reader_removes_its_staging_folder(tmp_path):
    # Written to standard output (/dev/stdout) whose reader has gone, the FMU ends the command by
    # SIGPIPE, quietly, once its staging folder (a copy of the whole runtime) is removed.
    runtime = stand_in_runtime(tmp_path / "runtime", "binary")
    staging = tmp_path / "staging"
    staging.mkdir()
    out = run_into_a_pipe_without_a_reader("fmu", MODELS / "oscillator.json", "-o", "/dev/stdout", "--runtime", runtime,
                                           env=dict(os.environ, TMPDIR=str(staging)))
    assert out.returncode == -signal.SIGPIPE and out.stderr == "", (out.returncode, out.stderr)
    assert list(staging.iterdir()) == []
    # With SIGPIPE blocked from the start, which never ends the tool, the write fails with its
    # reason (exit status 1), the staging folder removed all the same.
    out = run_into_a_pipe_without_a_reader("fmu", MODELS / "oscillator.json", "-o", "/dev/stdout", "--runtime", runtime,
                                           env=dict(os.environ, TMPDIR=str(staging)), pipe_signal_blocked=True)
    assert out.returncode == 1 and out.stderr == "springmass fmu: cannot write /dev/stdout: Broken pipe\n", (
        out.returncode, out.stderr)
    assert list(staging.iterdir()) == []


@pytest.mark.skipif(not HAS_FMU, reason="a build without the FMU runtime")
def test_fmu_goes_on_through_a_hangup_under_nohup(tmp_path):
    # Started with SIGHUP ignored (nohup), the packaging goes on through one, as asked, and
    # writes the FMU. The stand-in zip sends it while the tool waits for zip, as in
    # test_fmu_stopped_by_a_signal_leaves_nothing_behind.
    runtime = stand_in_runtime(tmp_path / "runtime", "binary")
    tools = signalling_zip(tmp_path / "tools", "HUP")
    fmu = tmp_path / "oscillator.fmu"
    env = dict(os.environ, PATH=f"{tools}:{os.environ['PATH']}")
    out = subprocess.run([str(CLI), "fmu", str(MODELS / "oscillator.json"), "-o", str(fmu), "--runtime", str(runtime)],
                         capture_output=True, text=True, env=env, timeout=60,
                         preexec_fn=lambda: signal.signal(signal.SIGHUP, signal.SIG_IGN))
    assert out.returncode == 0, out.stderr
    with zipfile.ZipFile(fmu) as z:
        assert z.read("resources/model.json") == (MODELS / "oscillator.json").read_bytes()


@pytest.mark.skipif(not HAS_FMU, reason="a build without the FMU runtime")
def test_fmu_tells_a_zip_it_cannot_run_from_one_that_fails(tmp_path):
    # Without a zip to run the message asks whether zip is installed; a zip that ran and ended
    # without an archive, by an exit status of its own or by a signal (128 + its number, as a shell
    # reports it), is named as failing with that status. Either way nothing is left behind.
    runtime = stand_in_runtime(tmp_path / "runtime", "binary")
    staging = tmp_path / "staging"
    staging.mkdir()
    tools = tmp_path / "tools"
    tools.mkdir()
    fmu = tmp_path / "oscillator.fmu"
    env = dict(os.environ, TMPDIR=str(staging), PATH=str(tools))
    err = cli("fmu", MODELS / "oscillator.json", "-o", fmu, "--runtime", runtime, status=1, env=env).stderr
    assert re.fullmatch(re.escape(f"springmass fmu: cannot run zip in {staging}/") + r"springmass-fmu-[^/ ]+"
                        + re.escape(" (is zip installed?)\n"), err), err
    assert list(staging.iterdir()) == [] and not fmu.exists()
    for script, status in (("exit 1", 1), ("kill -KILL $$", 128 + signal.SIGKILL)):
        (tools / "zip").write_text(f"#!/bin/sh\n{script}\n")
        (tools / "zip").chmod(0o755)
        err = cli("fmu", MODELS / "oscillator.json", "-o", fmu, "--runtime", runtime, status=1, env=env).stderr
        assert re.fullmatch(re.escape(f"springmass fmu: zip failed to write the archive {staging}/")
                            + r"springmass-fmu-[^/ ]+/model\.fmu" + re.escape(f" (exit status {status})\n"), err), err
        assert list(staging.iterdir()) == [] and not fmu.exists()


@pytest.mark.skipif(not HAS_FMU, reason="a build without the FMU runtime")
def test_fmu_names_the_staging_place_it_cannot_write(tmp_path):
    # The FMU is assembled in a staging folder in $TMPDIR: when that cannot be written (a full
    # disk, here a limit on the size of a file, which fails the same way), the message names the
    # file or folder there, not the runtime it copies or zip's installation, and nothing is left.
    # The runtime's stand-in library and licence are incompressible: the archive is as large as both.
    osc = MODELS / "oscillator.json"
    runtime = stand_in_runtime(tmp_path / "runtime", "binary")
    staging = tmp_path / "staging"
    staging.mkdir()
    fmu = tmp_path / "oscillator.fmu"
    limit = 100_000  # [bytes] the largest file the tool may write

    def package(library_bytes, tmpdir=staging):
        (runtime / "binaries" / "linux64" / "libextra.so.1").write_bytes(os.urandom(library_bytes))
        (runtime / "documentation" / "licenses" / "license.txt").write_bytes(os.urandom(library_bytes))

        def limited():
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails (EFBIG)
            resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

        out = subprocess.run([str(CLI), "fmu", osc, "-o", fmu, "--runtime", runtime], capture_output=True,
                             text=True, env=dict(os.environ, TMPDIR=str(tmpdir)), preexec_fn=limited, timeout=60)
        assert out.returncode == 1, out.stderr
        assert not fmu.exists() and list(staging.iterdir()) == []
        return out.stderr

    # A library larger than the limit cannot be copied into the staging folder.
    err = package(2 * limit)
    assert re.search(re.escape(f"cannot copy the FMU runtime from {runtime}/binaries/linux64: cannot write {staging}/")
                     + r"springmass-fmu-[^/]+/binaries/linux64/libextra\.so\.1: File too large$", err), err
    # Each file fits, the archive of them does not: zip fails and says why.
    err = package(limit * 3 // 4)
    assert re.search(re.escape(f"zip failed to write the archive {staging}/")
                     + r"springmass-fmu-[^/]+/model\.fmu \(exit status \d+\)$", err), err
    assert "installed" not in err
    # A $TMPDIR that does not exist.
    err = package(1000, tmpdir=tmp_path / "none")
    assert err == (f"springmass fmu: cannot create a staging folder in {tmp_path / 'none'} ($TMPDIR): "
                   "No such file or directory\n")


@pytest.mark.skipif(not HAS_FMU, reason="a build without the FMU runtime")
def test_fmu_documentation_page(tmp_path):
    # documentation/index.html shows the model's description as text, whatever characters it holds
    # (markup, quotes, ampersands, letters beyond ASCII; a name is an identifier), and links the licences only when the runtime
    # has them (a runtime assembled before they were gathered has none).
    model = json.loads((MODELS / "oscillator.json").read_text())
    model["name"] = "odd_one"
    model["description"] = 'A <b>bold</b> "claim" & more: Größe 1 µm'
    path = tmp_path / "odd.json"
    path.write_text(json.dumps(model))
    with_licences = stand_in_runtime(tmp_path / "with", "binary")
    without = stand_in_runtime(tmp_path / "without", "binary")
    shutil.rmtree(without / "documentation")
    for runtime, links in ((with_licences, ["licenses/license.txt"]), (without, [])):
        fmu = tmp_path / "odd.fmu"
        cli("fmu", path, "--output", fmu, "--runtime", runtime)
        doc = read_documentation(fmu)
        assert doc.title == "odd_one"
        assert doc.paragraphs[""][0] == 'A <b>bold</b> "claim" & more: Größe 1 µm'
        assert doc.links == links
        with zipfile.ZipFile(fmu) as z:
            assert ("documentation/licenses/license.txt" in z.namelist()) == bool(links)
        fmu.unlink()


@pytest.mark.skipif(not HAS_FMU, reason="a build without the FMU runtime")
def test_fmu_descriptions_read_back_as_the_model_file_gives_them(tmp_path):
    # A description may hold tabs, and it and a particle's name any character but controls and
    # line breaks, the noncharacters U+FFFE and U+FFFF too, which XML 1.0 has no way to write:
    # modelDescription.xml stays well-formed (they read as U+FFFD) and a tab stays a tab (an
    # attribute's tab reads as a space unless written as a character reference).
    model = json.loads((MODELS / "oscillator.json").read_text())
    model["description"] = "tab\there, <&> \"'\uffff\ufffe end"
    model["particles"][1]["name"] = "bob\uffff&<>"
    model["springs"][0]["b"] = model["ports"][0]["particle"] = "bob\uffff&<>"
    path = tmp_path / "odd.json"
    path.write_text(json.dumps(model, ensure_ascii=False), encoding="utf-8")
    fmu = tmp_path / "odd.fmu"
    cli("fmu", path, "--output", fmu, "--runtime", stand_in_runtime(tmp_path / "runtime", "binary"))
    with zipfile.ZipFile(fmu) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    assert root.get("description") == "tab\there, <&> \"'\ufffd\ufffd end"
    variables = {v.get("name"): v.get("description") for v in root.iter("ScalarVariable")}
    assert variables["tip.x"] == "x of tip, position at the port at particle bob\ufffd&<>"
    assert variables["p[1].vz"] == "z-velocity of particle bob\ufffd&<>"
    assert read_documentation(fmu).paragraphs[""][0] == "tab\there, <&> \"'\ufffd\ufffd end"


@pytest.mark.skipif(not HAS_FMU, reason="a build without the FMU runtime")
def test_fmu_refuses_what_it_cannot_pack_and_writes_nothing(tmp_path):
    # -h prints the help as --help does; an unknown option is a usage error (2); a runtime folder
    # without the FMU binary, a reference that cannot be read and a broken model are errors (1),
    # each named, and none leaves an output or a staging folder behind.
    osc = MODELS / "oscillator.json"
    runtime = stand_in_runtime(tmp_path / "runtime", "binary")
    fmu = tmp_path / "x.fmu"
    staging = tmp_path / "staging"
    staging.mkdir()
    env = dict(os.environ, TMPDIR=str(staging))
    assert cli("fmu", "-h").stdout.startswith("usage: springmass fmu")
    out = cli("fmu", osc, "-o", fmu, "--runtime", runtime, "--frobnicate", status=2, env=env)
    assert out.stderr.startswith("springmass fmu: unknown option or missing value: --frobnicate")
    # The message says where it looked for the runtime.
    (tmp_path / "empty").mkdir()
    out = cli("fmu", osc, "-o", fmu, "--runtime", tmp_path / "empty", status=1, env=env)
    assert out.stderr.startswith("springmass fmu: no FMU runtime (binaries/linux64/springmass_fmu.so) in "
                                 f"{tmp_path / 'empty'};")
    # ... and where that place came from, when the environment named it.
    out = cli("fmu", osc, "-o", fmu, status=1, env=dict(env, SPRINGMASS_FMU_RUNTIME=str(tmp_path / "empty")))
    assert out.stderr.startswith("springmass fmu: no FMU runtime (binaries/linux64/springmass_fmu.so) in "
                                 f"{tmp_path / 'empty'} (from $SPRINGMASS_FMU_RUNTIME);")
    out = cli("fmu", osc, "-o", fmu, "--runtime", runtime, "--reference", tmp_path / "missing.csv", status=1, env=env)
    assert out.stderr == (f"springmass fmu: cannot read the reference result {tmp_path / 'missing.csv'}: "
                          "No such file or directory\n")
    out = cli("fmu", osc, "-o", fmu, "--runtime", runtime, "--reference", "/dev/null", status=1, env=env)
    assert out.stderr == "springmass fmu: cannot read the reference result /dev/null: not a regular file\n"
    # A broken model is refused with the loader's message, as `springmass check` gives it.
    broken = ROOT / "tests" / "bad_models" / "unknown_particle.json"
    out = cli("fmu", broken, "-o", fmu, "--runtime", runtime, status=1, env=env)
    assert out.stderr == f'springmass fmu: {broken}: springs[3].b: no particle named "bobb"\n'
    assert not fmu.exists() and list(staging.iterdir()) == []


@pytest.mark.skipif(not HAS_FMU, reason="a build without the FMU runtime")
def test_fmu_writes_values_the_file_order_cannot_take_where_each_was_last_set(tmp_path):
    # docs/fmu.md: when no pass over the file's order takes the values, they are written in the
    # order of the --set options, each parameter where it was last set. Two ropes start at
    # (a, b, c) and (a, c, b), from (0, 0, 0), and end at (1, 1, 0) and (1, 5, 0): the file's order
    # takes a = 1 first, and then b = 1 or c = 5 puts a rope's start on its end. Here b is set
    # again after c: where each was last set, c=5, b=1, a=1 keeps both ropes long, as the order
    # where each was first set (b=1, c=5, a=1) would too; the former is written.
    model = tmp_path / "two_starts.json"
    model.write_text('{"springmass": 1, "name": "two_starts", "parameters": {"a": 0, "b": 0, "c": 0}, '
                     '"structures": [{"type": "rope", "name": "r1", "start": ["a", "b", "c"], "end": [1, 1, 0], '
                     '"segments": 1, "structural": {"strain_stiffness": 10}}, {"type": "rope", "name": "r2", '
                     '"start": ["a", "c", "b"], "end": [1, 5, 0], "segments": 1, '
                     '"structural": {"strain_stiffness": 10}}]}')
    runtime = stand_in_runtime(tmp_path / "runtime", "binary")
    fmu = tmp_path / "two_starts.fmu"
    cli("fmu", model, "-o", fmu, "--runtime", runtime, "--set", "b=1", "--set", "c=5", "--set", "b=1", "--set", "a=1")
    with zipfile.ZipFile(fmu) as z:
        assert z.read("resources/parameters.txt") == b"c=5\nb=1\na=1\n"


@pytest.mark.parametrize("command", ["check", "run", "statics", "modes",
                                     pytest.param("fmu", marks=pytest.mark.skipif(
                                         not HAS_FMU, reason="a build without the FMU runtime"))])
def test_every_command_refuses_a_missing_or_second_model_file_and_unknown_options(command, tmp_path):
    # One model file per call: none, two, or an option no command knows is a usage error (exit 2),
    # said the same way by every command and followed by its usage; nothing is written.
    osc, cloth = MODELS / "oscillator.json", MODELS / "cloth.json"
    output = ["-o", tmp_path / "out"] if command in ("fmu", "run") else []
    cases = (([], "no model file given"),
             ([osc, cloth], f"one model file at a time ('{osc}' and '{cloth}' given)"),
             (["--frobnicate", osc], "unknown option or missing value: --frobnicate"))
    for args, message in cases:
        out = cli(command, *args, *output, status=2)
        assert out.stderr.startswith(f"springmass {command}: {message}\n"), out.stderr
        assert f"usage: springmass {command}" in out.stderr, out.stderr
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "model, sets, solver",
    [
        ("oscillator", [], "dense"),
        ("two_mass_chain", [], "dense"),
        ("hanging_rope", ["n=3"], "pcg"),
        ("cloth", ["n=3"], "pcg"),
        ("hanging_rope", [], "pcg"),
    ],
)
def test_run_summary_names_the_solver_auto_picks(tmp_path, model, sets, solver):
    """The default solver is dense up to 2 free particles and pcg above (docs/simulation.md): from 3
    free particles on SUNDIALS' dense LU takes 1.5 - 5 times the time of pcg (bench/README.md), as
    on the 7 free particles of the 3 x 3 cloth. The summary names the solver in use."""
    args = [x for kv in sets for x in ("--set", kv)]
    out = cli("run", MODELS / f"{model}.json", *args, "--t-end", 0.1, "-o", tmp_path / "out.csv")
    assert re.search(rf" with BDF, solver {solver}: ", out.stderr), out.stderr


@pytest.mark.parametrize("option, value", [("--step", "0"), ("--stop-time", "-1"), ("--step", "inf"),
                                           ("--stop-time", "nan"), ("--step", "1e400"), ("--stop-time", "2 s")])
def test_the_fmu_demo_refuses_times_that_are_not_above_zero(tmp_path, option, value):
    # A zero step or stop time used to fall back silently to the FMU's default experiment; an
    # infinite one (1e400 reads as inf) is above 0 but no time, and text that is no number at all
    # gets the same message rather than one naming the demo's internal argument parser.
    run = subprocess.run([sys.executable, ROOT / "tools" / "fmu_demo.py", tmp_path / "absent.fmu",
                          tmp_path / "plot.png", option, value], capture_output=True, text=True)
    assert run.returncode == 2
    assert f"argument {option}: {value} is not a finite time above 0 s" in run.stderr
    assert not (tmp_path / "plot.png").exists()


def demo_copy(tmp_path):
    """A copy of tools/demo.sh beside the bundled models, as in a checkout: the script finds the
    models, the plotting script and the Python environment (.venv, here the tests' own when they run
    in one) from its own place and writes into out/demo/ there, not into this checkout."""
    root = tmp_path / "checkout"
    (root / "tools").mkdir(parents=True)
    for name in ("demo.sh", "fmu_demo.py"):
        shutil.copy2(ROOT / "tools" / name, root / "tools" / name)
    (root / "models").symlink_to(ROOT / "models")
    if sys.prefix != sys.base_prefix:
        (root / ".venv").symlink_to(sys.prefix)
    return root


def test_the_demo_leaves_no_earlier_results_when_a_step_fails(tmp_path):
    """A build without FMU support stops the demo at `springmass fmu`, with the tool's message. The
    FMU and the plot that an earlier run (of a build with FMUs) left in out/demo/ are gone, not left
    beside this run's cloth as if this run had made them. The build here is the tool behind a
    script that refuses `fmu` as a build without the FMU runtime does."""
    root = demo_copy(tmp_path)
    build = tmp_path / "build"
    (build / "tools").mkdir(parents=True)
    tool = build / "tools" / "springmass"
    tool.write_text('#!/bin/sh\n[ "$1" != fmu ] || { echo "springmass fmu: this build has no FMU support" >&2; '
                    f'exit 1; }}\nexec "{CLI}" "$@"\n')
    tool.chmod(0o755)
    out = root / "out" / "demo"
    out.mkdir(parents=True)
    for name in ("oscillator.fmu", "oscillator.png"):
        (out / name).write_bytes(b"an earlier run's")
    run = subprocess.run([root / "tools" / "demo.sh", build], capture_output=True, text=True, timeout=120)
    assert run.returncode == 1, run.stderr
    assert "springmass fmu: this build has no FMU support" in run.stderr
    assert "Results in" not in run.stdout
    assert sorted(p.name for p in out.iterdir()) == ["cloth.csv", "cloth_vtk"]
    header, rows = read_csv(out / "cloth.csv")
    assert rows[-1, 0] == 2.0  # the demo's cloth runs to 2 s


@pytest.mark.skipif(not HAS_FMU or SANITIZED, reason="a build without the FMU runtime; a sanitizer's shadow memory")
def test_the_demo_names_where_its_results_are_from_any_folder(tmp_path):
    """The demo run from another folder than the checkout's: the folder its closing text names,
    taken from where it was run, holds every file the text lists, and they are what it says they
    are: the CSV's columns, a series that indexes a frame per CSV row, an FMU and a PNG."""
    root = demo_copy(tmp_path)
    if not (root / ".venv").exists():
        pytest.skip("the tests' Python is no virtual environment to stand for .venv")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    run = subprocess.run([root / "tools" / "demo.sh", CLI.parent.parent], cwd=elsewhere, capture_output=True,
                         text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    folder = elsewhere / re.search(r"^Results in (.+):$", run.stdout, re.M).group(1)
    listed = re.findall(r"^  (\S+) ", run.stdout.split("Results in", 1)[1], re.M)
    assert listed == ["cloth.csv", "cloth_vtk/cloth.pvd", "oscillator.fmu", "oscillator.png"]
    assert all((folder / name).is_file() for name in listed)
    header, rows = read_csv(folder / "cloth.csv")
    assert header[0] == "time" and "corner.z" in header and "energy.kinetic" in header
    frames = ET.parse(folder / "cloth_vtk" / "cloth.pvd").getroot().findall(".//DataSet")
    assert [float(f.get("timestep")) for f in frames] == list(rows[:, 0])
    assert all((folder / "cloth_vtk" / f.get("file")).is_file() for f in frames)
    assert zipfile.is_zipfile(folder / "oscillator.fmu")
    assert (folder / "oscillator.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("missing", ["build", ".venv"])
def test_the_demo_says_what_is_missing_before_it_starts(tmp_path, missing):
    """A build folder without the tool (not built yet) or a checkout without the Python environment
    (tools/setup.sh not run) stops the demo before it removes or writes anything, with a message
    that names what is missing and what makes it."""
    root = demo_copy(tmp_path)
    build = CLI.parent.parent
    if missing == "build":
        build = tmp_path / "build"
        build.mkdir()
    elif (root / ".venv").exists() or (root / ".venv").is_symlink():
        (root / ".venv").unlink()
    out = root / "out" / "demo"
    out.mkdir(parents=True)
    (out / "cloth.csv").write_text("an earlier run's")
    run = subprocess.run([root / "tools" / "demo.sh", build], capture_output=True, text=True, timeout=120)
    assert run.returncode == 1, run.stderr
    assert run.stdout == ""
    said = {"build": f"no springmass tool in {build}: build it first (make build)",
            ".venv": f"no Python environment in {root / '.venv'}: make it with tools/setup.sh"}[missing]
    assert run.stderr == f"demo: {said}\n"
    assert (out / "cloth.csv").read_text() == "an earlier run's"


# A name holding what a terminal acts on (ESC [31m turns the text red), a line break, and a byte
# that begins no UTF-8 character (passed to the tool as the byte 0xff), and how messages show it:
# escaped as the library shows a model file's path, so that every message stays one plain line.
TERMINAL_NAME = "x\x1b[31mred\nline\udcff"
TERMINAL_NAME_SHOWN = "x\\u001b[31mred\\u000aline\\xff"


def messages_naming_paths(tmp_path):
    """(arguments, exit status, message) for each kind of message that names a path the user gave,
    each path holding TERMINAL_NAME."""
    model = tmp_path / f"model{TERMINAL_NAME}.json"
    shutil.copy(MODELS / "oscillator.json", model)
    shown = str(tmp_path) + "/model" + TERMINAL_NAME_SHOWN + ".json"
    a_file = tmp_path / f"file{TERMINAL_NAME}"
    a_file.write_text("")
    file_shown = f"{tmp_path}/file{TERMINAL_NAME_SHOWN}"
    full = tmp_path / f"full{TERMINAL_NAME}"
    full.symlink_to("/dev/full")
    malformed = tmp_path / f"signals{TERMINAL_NAME}.csv"
    malformed.write_text("time,tip.x\n0,1\n")
    cases = [
        # An output that cannot be written: checked before the run, and failed at the write.
        (["run", OSC, "-q", "-o", a_file / "out.csv"], 1,
         f"springmass run: -o {file_shown}/out.csv: cannot write there: the folder it would go in is a file"),
        (["run", OSC, "-q", "-o", full], 1,
         f"springmass run: cannot write {tmp_path}/full{TERMINAL_NAME_SHOWN}: No space left on device"),
        (["statics", OSC, "-q", "--save-model", tmp_path / f"none{TERMINAL_NAME}" / "x.json"], 1,
         f"springmass statics: --save-model {tmp_path}/none{TERMINAL_NAME_SHOWN}/x.json: cannot write there: "
         "the folder it would go in does not exist"),
        # Input signals refused: missing, and read but wrong.
        (["run", OSC, "-q", "-o", "-", "--input", tmp_path / f"none{TERMINAL_NAME}.csv"], 1,
         f"springmass run: cannot read the input signals {tmp_path}/none{TERMINAL_NAME_SHOWN}.csv: "
         "No such file or directory"),
        (["run", MODELS / "hanging_rope.json", "-q", "-o", "-", "--input", malformed], 1,
         f"springmass run: --input {tmp_path}/signals{TERMINAL_NAME_SHOWN}.csv:1:6: \"tip.x\" is a probe's: "
         "a probe takes no input"),
        # A --vtk folder refused.
        (["run", OSC, "-q", "-o", "-", "--vtk", a_file], 1,
         f"springmass run: --vtk {file_shown}: cannot write there: a file of that name exists"),
        (["modes", OSC, "-o", tmp_path / "modes.csv", "--vtk", a_file], 1,
         f"springmass modes: --vtk {file_shown}: cannot write there: a file of that name exists"),
        # The model file: missing (the library's message), an output onto it, or two given.
        (["check", tmp_path / f"none{TERMINAL_NAME}.json"], 1,
         f"springmass check: {tmp_path}/none{TERMINAL_NAME_SHOWN}.json: cannot open: No such file or directory"),
        (["run", model, "-q", "-o", model], 2,
         f"springmass run: -o {shown} would overwrite the model file {shown}, which it reads; give another name"),
        (["check", model, model], 2,
         f"springmass check: one model file at a time ('{shown}' and '{shown}' given)\n"),
    ]
    if HAS_FMU:
        cases += [
            (["fmu", tmp_path / f"none{TERMINAL_NAME}.json", "-o", tmp_path / "out.fmu"], 1,
             f"springmass fmu: cannot read {tmp_path}/none{TERMINAL_NAME_SHOWN}.json: No such file or directory"),
            (["fmu", OSC, "-o", tmp_path / "out.fmu", "--runtime", tmp_path / f"runtime{TERMINAL_NAME}"], 1,
             f"springmass fmu: no FMU runtime (binaries/linux64/springmass_fmu.so) in "
             f"{tmp_path}/runtime{TERMINAL_NAME_SHOWN}; give one with --runtime"),
        ]
    return cases


def test_messages_show_the_paths_they_name_escaped_on_one_line(tmp_path):
    # Each message is one line, the whole of standard error but for a usage error's help, which
    # follows it after a blank line (a message ending in "\n" here): the name's ESC and line break
    # would otherwise split it.
    for args, status, message in messages_naming_paths(tmp_path):
        # Bytes that are not UTF-8 in the message (the name's 0xff written as it is) replaced.
        out = subprocess.run([str(CLI), *map(str, args)], capture_output=True, text=True, errors="replace", timeout=60)
        assert out.returncode == status, (args, out.stderr)
        err = out.stderr
        line, _, rest = err.partition("\n")
        assert line == message.rstrip("\n"), (args, err)
        assert rest == "" if not message.endswith("\n") else rest.startswith("\nusage: "), (args, err)
        assert "\x1b" not in err


def messages_echoing_arguments():
    """(arguments, environment, exit status, message) for each kind of message that repeats other
    text of the command line than a path (an unknown command or option, a refused value, a --set
    and its parameter's name) or of the environment, each text holding TERMINAL_NAME."""
    t, shown = TERMINAL_NAME, TERMINAL_NAME_SHOWN
    cases = [
        (["bogus" + t], None, 2, f"springmass: unknown command 'bogus{shown}'\n"),
        (["help", "bogus" + t], None, 2, f"springmass: unknown command 'bogus{shown}'\n"),
        (["check", OSC, "--bogus" + t], None, 2, f"springmass check: unknown option or missing value: --bogus{shown}\n"),
        # --set: no NAME=, a name too long, a value that is no number, a parameter the model lacks.
        (["check", OSC, "--set", t], None, 2, f"springmass check: --set expects NAME=VALUE, got '{shown}'"),
        (["check", OSC, "--set", t + "a" * 300 + "=1"], None, 2,
         f"springmass check: --set {shown}{'a' * 300}=1: the parameter's name is too long (255 bytes at most)"),
        (["check", OSC, "--set", "k=" + t], None, 2,
         f"springmass check: --set k={shown}: '{shown}' is not a finite number"),
        (["check", OSC, "--set", t + "=1"], None, 1,
         f"springmass check: --set {shown}=1: the model has no parameter named \"{shown}\""),
        # Values refused by run, statics and modes.
        (["run", OSC, "--t-end", t], None, 2, f"springmass run: --t-end expects a finite number, got '{shown}'"),
        (["run", OSC, "--threads", t], None, 2, f"springmass run: --threads needs a count from 1 to 1024, got '{shown}'"),
        (["run", OSC, "--max-steps", t], None, 2,
         f"springmass run: --max-steps needs a count from 1 to 2e9, got '{shown}'"),
        (["run", OSC, "--max-step", t], None, 2,
         f"springmass run: --max-step needs a step >= 0 [s] (0: no limit), got '{shown}'"),
        (["run", OSC, "--stability-limit-detection", t], None, 2,
         f"springmass run: --stability-limit-detection takes on or off, got '{shown}'"),
        (["run", OSC, "-q", "-o", "-", "--solver", t], None, 2,
         f"springmass run: --solver: unknown linear solver '{shown}' (auto, dense, klu, pcg, cholmod)"),
        (["run", OSC, "-q", "-o", "-", "--method", t], None, 2, f"springmass run: --method: unknown method '{shown}' (bdf, adams)"),
        (["run", OSC, "-q", "-o", "-", "--jacobian", t], None, 2,
         f"springmass run: --jacobian: unknown Jacobian '{shown}' (exact, definite)"),
        (["run", OSC, "-q", "-o", "-", "--input-changes", t], None, 2,
         f"springmass run: unknown --input-changes '{shown}' (restart, keep)"),
        (["statics", OSC, "--max-iterations", t], None, 2,
         f"springmass statics: --max-iterations needs a count from 1 to 1000000, got '{shown}'"),
        (["statics", OSC, "--solver", t], None, 2, f"springmass statics: --solver: unknown solver '{shown}' (auto, dense, sparse)"),
        (["modes", OSC, "-n", t], None, 2, f"springmass modes: -n needs a count from 0 to 1e8, got '{shown}'"),
        (["modes", OSC, "--zero-tolerance", t], None, 2,
         f"springmass modes: --zero-tolerance needs a number in [0, 1), got '{shown}'"),
        (["modes", OSC, "--steps-per-period", t], None, 2,
         f"springmass modes: --steps-per-period needs a finite number >= 1, got '{shown}'"),
        (["statics", OSC, "--tolerance", t], None, 2,
         f"springmass statics: --tolerance needs a positive finite number of newtons, got '{shown}'"),
        (["modes", OSC, "--solver", t], None, 2, f"springmass modes: --solver: unknown solver '{shown}' (auto, dense, sparse)"),
    ]
    if HAS_FMU:
        cases += [
            (["fmu", OSC, "-o", "out.fmu"], {**os.environ, "SOURCE_DATE_EPOCH": "1" + t}, 2,
             f"springmass fmu: SOURCE_DATE_EPOCH '1{shown}' is not a count of seconds since 1970"),
        ]
    return cases


def test_messages_show_the_arguments_they_repeat_escaped_on_one_line(tmp_path):
    # As the paths above: each message one line (a usage error's help after a blank line), the
    # argument's ESC, line break and stray byte escaped; an ordinary argument is shown as it is.
    for args, env, status, message in messages_echoing_arguments():
        out = subprocess.run([str(CLI), *map(str, args)], capture_output=True, text=True, errors="replace",
                             env=env, cwd=tmp_path, timeout=60)
        assert out.returncode == status, (args, out.stderr)
        err = out.stderr
        line, _, rest = err.partition("\n")
        assert line == message.rstrip("\n"), (args, err)
        assert rest == "" if not message.endswith("\n") else rest.startswith("\nusage: "), (args, err)
        assert "\x1b" not in err
    plain = cli("run", OSC, "--solver", "fast", status=2).stderr
    assert plain == "springmass run: --solver: unknown linear solver 'fast' (auto, dense, klu, pcg, cholmod)\n", plain


def test_a_refused_value_names_the_option_it_came_from():
    # Every value refused says which option gave it: a name such as "sparse" or "bdf" alone does
    # not tell which of the command's options took it (run has --solver, --method, --jacobian and
    # --input-changes, each with its own names).
    long_name = "n" * 256
    for args, message in [
            (["run", OSC, "-q", "-o", "-", "--solver", "fast"],
             "springmass run: --solver: unknown linear solver 'fast' (auto, dense, klu, pcg, cholmod)"),
            (["run", OSC, "-q", "-o", "-", "--method", "rk4"], "springmass run: --method: unknown method 'rk4' (bdf, adams)"),
            (["run", OSC, "-q", "-o", "-", "--jacobian", "bdf"],
             "springmass run: --jacobian: unknown Jacobian 'bdf' (exact, definite)"),
            (["statics", OSC, "--solver", "klu"], "springmass statics: --solver: unknown solver 'klu' (auto, dense, sparse)"),
            (["modes", OSC, "--solver", "klu"], "springmass modes: --solver: unknown solver 'klu' (auto, dense, sparse)"),
            (["check", OSC, "--set", long_name + "=1"],
             f"springmass check: --set {long_name}=1: the parameter's name is too long (255 bytes at most)")]:
        assert cli(*args, status=2).stderr == message + "\n", args


def test_reports_show_the_paths_of_their_outputs_escaped(tmp_path):
    # What statics and modes print on standard output after writing: the paths named as in the
    # messages (the folder's ESC, line break and stray byte escaped), each report line one line.
    folder = tmp_path / f"out{TERMINAL_NAME}"
    folder.mkdir()
    shown = f"{tmp_path}/out{TERMINAL_NAME_SHOWN}"

    def report(*args):
        out = subprocess.run([str(CLI), *map(str, args)], capture_output=True, text=True, errors="replace", timeout=60)
        assert out.returncode == 0, (args, out.stderr)
        assert "\x1b" not in out.stdout
        return out.stdout.splitlines()

    lines = report("statics", OSC, "-q", "-o", folder / "shape.csv", "--vtk", folder / "vtk", "--save-model",
                   folder / "rest.json")
    assert lines[-3:] == [f"rest shape written to {shown}/shape.csv",
                          f"rest shape written to {shown}/vtk/statics.vtk (open it in ParaView)",
                          f"model starting at rest saved to {shown}/rest.json"], lines
    # The oscillator's one free particle has 3 modes; then 1 of them, and the 2 files beyond removed.
    lines = report("modes", OSC, "-o", folder / "modes.csv", "--vtk", folder / "modes")
    assert lines[-2:] == [f"mode shapes written to {shown}/modes.csv",
                          f"mode shapes written to {shown}/modes/mode_<k>.vtk, k = 1 to 3 (open them in ParaView)"], lines
    lines = report("modes", OSC, "-n", 1, "--vtk", folder / "modes")
    assert lines[-2:] == [f"mode shapes written to {shown}/modes/mode_<k>.vtk, k = 1 to 1 (open them in ParaView)",
                          f"removed {shown}/modes/mode_2.vtk to mode_3.vtk, left there by an earlier run with more modes"], lines
    report("modes", OSC, "--vtk", folder / "modes")
    lines = report("modes", OSC, "-n", 2, "--vtk", folder / "modes")
    assert lines[-1] == f"removed {shown}/modes/mode_3.vtk, left there by an earlier run with more modes", lines
