"""Misuse of the FMU: each an error with a clear message, never a crash; usable after reset."""
import json
import math
import os
import re
import struct
import subprocess
import sys
import zipfile

import fmpy
import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from conftest import CLI, MODELS, ROOT
from fmu_helpers import Instance, fmu_guid

FMI2_ERROR = 3


def expect_error(inst, call, *words):
    """Runs call(), which must fail with fmi2Error and log a message containing all words."""
    before = len(inst.messages)
    with pytest.raises(FMICallException) as info:
        call()
    assert info.value.status == FMI2_ERROR
    text = "\n".join(m[2] for m in inst.messages[before:])
    for word in words:
        assert word in text, (word, text)
    assert all(m[1] == "logStatusError" for m in inst.messages[before:])


def test_wrong_guid_is_refused_with_a_message(test_fmu):
    inst = Instance(test_fmu("driven_oscillator"), guid="{00000000-0000-0000-0000-000000000000}",
                    instantiate=False)
    try:
        with pytest.raises(Exception):
            inst.slave.instantiate(callbacks=inst.callbacks)
        assert "does not match the model file" in inst.log_text()
    finally:
        inst.free()


def test_changed_model_file_is_refused(test_fmu, tmp_path):
    inst = Instance(test_fmu("driven_oscillator"), instantiate=False)
    try:
        model = f"{inst.unzipdir}/resources/model.json"
        with open(model, "a") as f:
            f.write("\n")
        with pytest.raises(Exception):
            inst.slave.instantiate(callbacks=inst.callbacks)
        assert "does not match the model file" in inst.log_text()
    finally:
        inst.free()


def test_model_exchange_is_refused(test_fmu):
    inst = Instance(test_fmu("driven_oscillator"), instantiate=False)
    try:
        comp = inst.slave.fmi2Instantiate(b"me", 0, inst.md.guid.encode(),
                                         f"file://{inst.unzipdir}/resources".encode(), inst.callbacks, 0, 0)
        assert comp is None
        assert "Co-Simulation only" in inst.log_text()
    finally:
        inst.free()


def test_call_sequence_and_arguments_are_checked(test_fmu):
    inst = Instance(test_fmu("driven_oscillator"))
    s, vr = inst.slave, inst.vr
    try:
        expect_error(inst, lambda: s.doStep(0.0, 0.1), "fmi2DoStep", "illegal call sequence")
        expect_error(inst, lambda: s.getReal([vr["tip.x"]]), "illegal call sequence")
        expect_error(inst, lambda: s.exitInitializationMode(), "illegal call sequence")
        inst.start()
        expect_error(inst, lambda: s.setupExperiment(startTime=0.0), "illegal call sequence")
        expect_error(inst, lambda: s.doStep(0.5, 0.1), "communication point", "does not match")
        expect_error(inst, lambda: s.doStep(0.0, -0.1), "must be finite and > 0")
        expect_error(inst, lambda: s.doStep(0.0, 0.0), "must be finite and > 0")
        expect_error(inst, lambda: s.setReal([vr["tip.fx"]], [math.nan]), "tip.fx", "finite")
        expect_error(inst, lambda: s.setReal([vr["base.x"]], [math.inf]), "base.x", "finite")
        expect_error(inst, lambda: s.getReal([100000]), "unknown value reference 100000")
        expect_error(inst, lambda: s.setReal([100000], [1.0]), "unknown value reference 100000")
        expect_error(inst, lambda: s.getInteger([vr["tip.x"]]), "is a Real variable")
        expect_error(inst, lambda: s.getBoolean([vr["tip.x"]]), "is a Real variable, not Boolean")
        expect_error(inst, lambda: s.setReal([vr["tip.x"]], [1.0]), "tip.x", "output")
        expect_error(inst, lambda: s.setReal([vr["solver.rtol"]], [1e-3]), "fixed parameter")
        expect_error(inst, lambda: s.setReal([vr["m"]], [-1.0]), "m = -1")
        expect_error(inst, lambda: s.setString([vr["solver.linear_solver"]], ["fast"]), "fixed parameter")
        # Every solver setting is a fixed parameter (docs/fmu.md), the Integer one too: after
        # initialisation any value of it is refused.
        assert all(v.variability == "fixed" for v in inst.md.modelVariables if v.name.startswith("solver."))
        expect_error(inst, lambda: s.setInteger([vr["solver.max_steps"]], [10]), "solver.max_steps", "fixed parameter")
        expect_error(inst, lambda: s.setBoolean([vr["solver.stability_limit_detection"]], [False]),
                     "solver.stability_limit_detection", "fixed parameter")
        expect_error(inst, lambda: s.getDirectionalDerivative([vr["base.fx"]], [vr["m"]], [1.0]), "not an input")
        expect_error(inst, lambda: s.setDebugLogging(True, ["logNothing"]), "unknown log category")
        expect_error(inst, lambda: s.cancelStep() if hasattr(s, "cancelStep") else s.fmi2CancelStep(s.component),
                     "synchronous")
        # NULL arrays through the raw API.
        expect_error(inst, lambda: s.fmi2GetReal(s.component, None, 1, None), "NULL array")
        # After all that the instance still steps, and a rejected value left nothing behind.
        s.doStep(0.0, 0.1)
        assert inst.get("tip.fx") == 0.0
        assert inst.get("m") == 2.0
    finally:
        inst.free()


def categories_logged(inst, t):
    """The categories of the messages one round logs: a step from t (logSolver), the tunable
    parameter k set (logEvents) and an output set (logStatusError)."""
    n = len(inst.messages)
    inst.slave.doStep(t, 0.1)
    inst.set("k", 51.0 + 10 * t)
    with pytest.raises(FMICallException):
        inst.slave.setReal([inst.vr["tip.x"]], [1.0])
    return {m[1] for m in inst.messages[n:]}


def test_debug_logging_logs_exactly_the_categories_asked_for(test_fmu):
    # FMI 2.0 (2.1.5): logging on with categories outputs only those, also after another list;
    # logging on with none outputs every category; logging off with none leaves the problems
    # reported (errors), and with categories switches those off. Each round makes a message of
    # three categories: logSolver (a step), logEvents (a tunable parameter set), logStatusError.
    inst = Instance(test_fmu("driven_oscillator"), logging_on=True).start()
    s = inst.slave
    try:
        s.setDebugLogging(True, ["logEvents"])
        assert categories_logged(inst, 0.0) == {"logEvents"}
        s.setDebugLogging(True, ["logSolver"])
        s.setDebugLogging(True, ["logEvents", "logStatusError"])
        assert categories_logged(inst, 0.1) == {"logEvents", "logStatusError"}
        s.setDebugLogging(True, [])
        assert categories_logged(inst, 0.2) == {"logEvents", "logSolver", "logStatusError"}
        s.setDebugLogging(False, [])
        assert categories_logged(inst, 0.3) == {"logStatusError"}
        s.setDebugLogging(False, ["logStatusError"])
        assert categories_logged(inst, 0.4) == set()
    finally:
        inst.free()


def test_relative_tolerance_of_one_or_more_is_refused(test_fmu):
    # A relative tolerance of 1 allows a 100 % error: refused at set-up and as a parameter, and
    # the instance goes on with its own.
    inst = Instance(test_fmu("driven_oscillator"))
    s, vr = inst.slave, inst.vr
    try:
        expect_error(inst, lambda: s.setupExperiment(tolerance=10.0, startTime=0.0), "tolerance 10", "(0, 1)")
        # From mutation testing: 1 itself, the bound, is refused at set-up as well; a check that took
        # (0, 1] passed with 10 alone.
        expect_error(inst, lambda: s.setupExperiment(tolerance=1.0, startTime=0.0), "tolerance 1 ", "(0, 1)")
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        expect_error(inst, lambda: s.setReal([vr["solver.rtol"]], [1.0]), "solver.rtol = 1", "< 1")
        s.exitInitializationMode()
        s.doStep(0.0, 0.1)
        assert inst.get("solver.rtol") < 1.0
    finally:
        inst.free()


def lone_particle(package, tmp_path, name, height, mass, simulation=None):
    """The FMU of one free particle `bob` of `mass` [kg] at `height` [m], a probe port on it."""
    model = {"springmass": 1, "name": name, "simulation": simulation or {},
             "particles": [{"name": "bob", "position": [0, 0, height], "mass": mass}],
             "ports": [{"name": "bob", "particle": "bob", "kind": "probe"}]}
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps(model))
    return package(path)


def test_a_step_whose_energies_overflow_is_a_discard(package, tmp_path):
    # 1e218 kg at 1e98 m above the origin: its gravitational energy, m g z = 9.8e316 J, is beyond
    # the largest double, though every state is finite. A step to there cannot report its outputs:
    # fmi2Discard naming the output, the step's end the last successful time (where the state and
    # outputs are); reset recovers. The same for a step too short to integrate (below the clock's
    # resolution, 4 eps).
    inst = Instance(lone_particle(package, tmp_path, "heavy", 1e98, 1e218)).start()
    s = inst.slave
    try:
        for h in (0.1, 1e-17):
            with pytest.raises(FMICallException) as info:
                s.doStep(0.0, h)
            assert info.value.status == 2  # fmi2Discard
            assert s.getRealStatus(2) == h  # fmi2LastSuccessfulTime
            assert "energy.gravity overflows" in inst.messages[-1][2] and inst.messages[-1][1] == "logStatusDiscard"
            # The instance is in the step-failed state (FMI 2.0, 4.2.3): fmi2GetStatus tells of the
            # discard, and a further step is refused.
            assert s.getStatus(0) == 2  # fmi2DoStepStatus: fmi2Discard
            expect_error(inst, lambda: s.doStep(h, 0.1), "fmi2DoStep", "illegal call sequence")
            s.reset()
            inst.start()
    finally:
        inst.free()


def test_a_step_whose_reaction_alone_overflows_is_a_discard(package):
    # The reaction at a driven particle is no state of the integration, and it can overflow while
    # every energy stays finite: the motion port's 1e150 m/s through a damper of 1e160 N s/m is
    # 1e310 N, where the anchor's 1 kg has 5e299 J. A step too short to integrate (below the
    # clock's resolution) takes no solver step that could fail on it: the step's end is where the
    # output is checked, fmi2Discard naming it.
    inst = Instance(package(MODELS / "driven_oscillator.json", sets=("d=1e160",))).start()
    s = inst.slave
    try:
        s.doStep(0.0, 0.01)
        inst.set("base.vx", 1e150)
        with pytest.raises(FMICallException) as info:
            s.doStep(0.01, 1e-17)
        assert info.value.status == 2  # fmi2Discard
        assert "output base.fx overflows" in inst.messages[-1][2] and inst.messages[-1][1] == "logStatusDiscard"
        assert math.isfinite(inst.get("energy.kinetic")) and math.isfinite(inst.get("energy.elastic"))
    finally:
        inst.free()


def test_a_step_whose_input_work_alone_overflows_is_a_discard(package):
    # The inputs' work is no state of the integration either: the work of a driven particle's jumps
    # and its kinetic energy, each finite, may sum beyond the largest double. The motion port moved
    # to -2.45e153 m stretches the spring (50 N/m) to 25 (2.45e153)^2 = 1.5e308 J, the work of that
    # jump (a step); then set moving at 1.2e154 m/s, it gives the anchor's 1 kg 7.2e307 J: the
    # inputs' work, 2.2e308 J, overflows while the kinetic and the elastic energy are finite. Steps
    # too short to integrate check their outputs at their ends: fmi2Discard naming energy.input.
    inst = Instance(package(MODELS / "driven_oscillator.json")).start()
    s = inst.slave
    try:
        s.doStep(0.0, 0.01)
        inst.set("base.x", -2.45e153)
        s.doStep(0.01, 1e-17)
        assert inst.get("energy.input") == inst.get("energy.elastic") > 1.5e308
        inst.set("base.vx", 1.2e154)
        with pytest.raises(FMICallException) as info:
            s.doStep(s.getRealStatus(2), 1e-17)
        assert info.value.status == 2  # fmi2Discard
        assert "output energy.input overflows" in inst.messages[-1][2] and inst.messages[-1][1] == "logStatusDiscard"
        assert math.isfinite(inst.get("energy.kinetic")) and math.isfinite(inst.get("energy.elastic"))
    finally:
        inst.free()


def test_outputs_after_an_overflow_discard_are_at_the_last_successful_time(package, tmp_path):
    # 1e300 kg falling from rest: at 1000 s its kinetic energy, m (g t)^2 / 2 = 4.8e307 J, is
    # finite; at 3000 s, 4.3e308 J, it is not. The step from 1000 to 3000 s is discarded, and what
    # the master reads then (the position, the velocity) is at
    # fmi2LastSuccessfulTime, as FMI 2.0 has it for a discarded step: free fall to 1e-9 (the
    # integration's relative tolerance, 1e-10, on states of order g t^2).
    inst = Instance(lone_particle(package, tmp_path, "falling", 0.0, 1e300, {"rtol": 1e-10})).start()
    s = inst.slave
    g = 9.81
    try:
        s.doStep(0.0, 1000.0)
        with pytest.raises(FMICallException) as info:
            s.doStep(1000.0, 2000.0)
        assert info.value.status == 2  # fmi2Discard
        assert "energy.kinetic overflows" in inst.messages[-1][2], inst.messages[-1]
        t = s.getRealStatus(2)  # fmi2LastSuccessfulTime
        assert t == 3000.0
        z, vz = inst.get("bob.z", "bob.vz")
        assert z == pytest.approx(-0.5 * g * t * t, rel=1e-9) and vz == pytest.approx(-g * t, rel=1e-9)
    finally:
        inst.free()


def test_declared_ranges_are_the_ones_the_setters_accept(test_fmu):
    # The solver settings declare min (and the relative tolerance max) in modelDescription.xml:
    # each bound is accepted, the next double beyond it refused with a message, for every variable
    # that declares one. The Integers' next value beyond 1 is 0.
    inst = Instance(test_fmu("driven_oscillator"))
    try:
        ranged = [v for v in inst.md.modelVariables if v.min is not None or v.max is not None]
        assert {v.name for v in ranged} == {"solver.rtol", "solver.atol_position", "solver.atol_velocity",
                                           "solver.max_step", "solver.max_steps", "solver.threads"}
        for v in ranged:
            for bound, outward in ((v.min, -math.inf), (v.max, math.inf)):
                if bound is None:
                    continue
                bound = float(bound)
                inst.set(v.name, bound)
                beyond = bound - 1 if v.type == "Integer" else math.nextafter(bound, outward)
                expect_error(inst, lambda: inst.set(v.name, beyond), v.name, "rejected")
    finally:
        inst.free()


def test_a_max_step_without_an_inverse_is_refused_where_it_is_set(test_fmu):
    # CVODE takes 1 / solver.max_step, which must be a double: a limit at or below 1 / DBL_MAX is
    # refused by fmi2SetReal with a message, as a model file's max_step is, and the instance goes on
    # with the value it had; the next double above it is taken. Accepted, it made
    # fmi2ExitInitializationMode fail and left the instance in the error state.
    least = 1.0 / sys.float_info.max
    inst = Instance(test_fmu("driven_oscillator"))
    s = inst.slave
    try:
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        for value in (least, 1e-310, 5e-324):
            expect_error(inst, lambda: inst.set("solver.max_step", value), "solver.max_step", "rejected",
                         "5.562684646268003e-309")
        assert inst.get("solver.max_step") == 0.0
        inst.set("solver.max_step", math.nextafter(least, 1.0))
        inst.set("solver.max_step", 0.05)
        s.exitInitializationMode()
        s.doStep(0.0, 0.1)
        assert inst.get("solver.max_step") == 0.05
    finally:
        inst.free()


def test_a_max_step_of_zero_is_unlimited_and_a_negative_one_is_refused(test_fmu):
    # solver.max_step = 0 lifts the limit (docs/fmu.md), also after a limit was set; a negative
    # limit, however small, is refused with a message and the value set before stays.
    inst = Instance(test_fmu("driven_oscillator"))
    s = inst.slave
    try:
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        inst.set("solver.max_step", 0.05)
        inst.set("solver.max_step", 0.0)
        assert inst.get("solver.max_step") == 0.0
        inst.set("solver.max_step", 0.05)
        for value in (-1e-3, -0.5, -2.0):
            expect_error(inst, lambda: inst.set("solver.max_step", value), "solver.max_step", "rejected", ">= 0")
        assert inst.get("solver.max_step") == 0.05
        inst.set("solver.max_step", 0.0)
        s.exitInitializationMode()
        s.doStep(0.0, 0.1)
        assert inst.get("solver.max_step") == 0.0
    finally:
        inst.free()


def test_outputs_beyond_a_double_between_steps_are_a_warning(test_fmu):
    # A motion port set to 1e300 m: the spring's squared length overflows, and with it the reaction
    # and the elastic energy, though every input is finite. fmi2GetReal gives the values as they
    # are with fmi2Warning (fmpy raises only above it), naming the first; they read fmi2OK again
    # once the port is back.
    inst = Instance(test_fmu("driven_oscillator")).start()
    s = inst.slave
    try:
        s.doStep(0.0, 0.01)
        inst.set("base.x", 1e300)
        fx, energy = s.getReal([inst.vr["base.fx"], inst.vr["energy.elastic"]])
        assert not math.isfinite(fx) and not math.isfinite(energy)
        assert inst.messages[-1][1] == "logStatusWarning" and "base.fx is not finite" in inst.messages[-1][2]
        count = len(inst.messages)
        inst.set("base.x", 0.0)
        assert all(math.isfinite(v) for v in s.getReal([inst.vr["base.fx"], inst.vr["energy.elastic"]]))
        assert len(inst.messages) == count
    finally:
        inst.free()


def test_solver_failure_is_a_discard_with_the_time_reached(test_fmu):
    # Two internal steps cannot cover 1 s of a 5 rad/s oscillation at rtol 1e-10: the step is
    # discarded, the time reached is readable, and only reset or terminate are allowed then.
    inst = Instance(test_fmu("driven_oscillator")).start({"solver.max_steps": 2, "solver.rtol": 1e-10})
    s = inst.slave
    try:
        with pytest.raises(FMICallException) as info:
            s.doStep(0.0, 1.0)
        assert info.value.status == 2  # fmi2Discard
        reached = s.getRealStatus(2)  # fmi2LastSuccessfulTime
        # The two internal steps got somewhere (measured 1.8e-5 s), short of the step's end.
        assert 0.0 < reached < 1.0
        assert any(m[1] == "logStatusDiscard" for m in inst.messages)
        expect_error(inst, lambda: s.doStep(reached, 0.1), "illegal call sequence")
        s.reset()
        inst.start()
        s.doStep(0.0, 0.1)
    finally:
        inst.free()


def test_a_step_limit_discard_says_how_to_go_on_and_going_on_so_works(test_fmu):
    # 40 internal steps cannot cover 1 s of the 5 rad/s oscillation at rtol 1e-10. The discard's
    # message says what FMI 2.0 allows after it (no next fmi2DoStep, which is refused), and doing
    # what it says, restoring the state saved before the step and taking it in shorter steps,
    # brings the bob to its closed-form place, 0.5 + 0.2 cos(5 t) m at t = 1 s.
    inst = Instance(test_fmu("driven_oscillator")).start(
        {"solver.max_steps": 40, "solver.rtol": 1e-10, "solver.atol_position": 1e-12,
         "solver.atol_velocity": 1e-10})
    s = inst.slave
    try:
        saved = s.getFMUstate()
        with pytest.raises(FMICallException) as info:
            s.doStep(0.0, 1.0)
        assert info.value.status == 2  # fmi2Discard
        text = "\n".join(m[2] for m in inst.messages if m[1] == "logStatusDiscard")
        assert "next advance goes on" not in text, text
        for words in ("fmi2SetFMUstate", "40 internal steps solver.max_steps"):
            assert words in text, (words, text)
        reached = s.getRealStatus(2)  # fmi2LastSuccessfulTime
        # It cannot step on from there: it asks a master that does not restore to end the run.
        assert s.getBooleanStatus(3) == 1  # fmi2Terminated
        expect_error(inst, lambda: s.doStep(reached, 0.1), "illegal call sequence")
        s.setFMUstate(saved)
        s.freeFMUstate(saved)
        assert s.getBooleanStatus(3) == 0  # restored: it steps on
        h = 0.05
        for n in range(20):
            s.doStep(n * h, h)
        # rtol 1e-10 and atol 1e-12 m over 20 restarted steps: 1e-8 m is a hundred times the error
        # measured (8.7e-11 m).
        assert inst.get("tip.x") == pytest.approx(0.5 + 0.2 * math.cos(5.0), abs=1e-8)
    finally:
        inst.free()


def test_a_step_limit_discard_with_adams_on_a_stiff_model_names_the_method(test_fmu):
    # A 1 g bob on a 1e6 N/m spring damped by 100 N s/m, overdamped with decay rates 11 270 /s and
    # 88 730 /s: Adams holds its steps below about 1 / (88 730 /s), and its 100 000 steps end far
    # short of the 2 s step (measured 0.08 s). The discard says to take BDF, and BDF, after a
    # reset, takes the step and leaves the bob at rest at the spring's rest length, 0.5 m (the
    # slower decay has left e^-22540 of the 0.2 m it started from).
    stiff = {"m": 1e-3, "k": 1e6, "d": 100.0}
    inst = Instance(test_fmu("driven_oscillator")).start({**stiff, "solver.method": "adams"})
    s = inst.slave
    try:
        with pytest.raises(FMICallException) as info:
            s.doStep(0.0, 2.0)
        assert info.value.status == 2  # fmi2Discard
        text = "\n".join(m[2] for m in inst.messages if m[1] == "logStatusDiscard")
        assert "solver.method bdf" in text, text
        assert 0.0 < s.getRealStatus(2) < 2.0  # fmi2LastSuccessfulTime
        s.reset()
        inst.start({**stiff, "solver.method": "bdf"})
        s.doStep(0.0, 2.0)
        # At rest to the default tolerances (atol 1e-8 m).
        assert inst.get("tip.x") == pytest.approx(0.5, abs=1e-7)
    finally:
        inst.free()


def test_simulate_fmu_ends_at_a_discarded_step_with_the_results_up_to_there(test_fmu):
    # fmpy's simulate_fmu ends the run at fmi2LastSuccessfulTime when the FMU asks to terminate
    # after a discard; otherwise it tries the next step, which is refused, and raises, losing every
    # row. A force of 1e300 N from t = 0.25 s on makes the forces overflow at once: the step from
    # 0.25 s is discarded.
    signal = np.array([(0.0, 0.0), (0.25, 0.0), (0.25, 1e300), (1.0, 1e300)],
                      dtype=[("time", np.float64), ("tip.fx", np.float64)])
    r = fmpy.simulate_fmu(test_fmu("driven_oscillator"), stop_time=1.0, output_interval=0.05,
                          start_values={"solver.rtol": 1e-10, "solver.atol_position": 1e-12,
                                        "solver.atol_velocity": 1e-10},
                          input=signal, output=["tip.x"])
    assert r["time"][-1] == pytest.approx(0.25, abs=1e-12) and len(r) >= 6, r
    # Each row up to there is the closed form 0.5 + 0.2 cos(5 t) m (rtol 1e-10: 1e-8 m is a
    # hundred times the error of such a run).
    np.testing.assert_allclose(r["tip.x"], 0.5 + 0.2 * np.cos(5.0 * r["time"]), rtol=0, atol=1e-8)


def numbers_in(text):
    """The decimal numbers of a message, not the digits of names such as fmi2SetFMUstate."""
    return [float(x) for x in re.findall(r"(?<![\w.])[-+]?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?", text)]


def test_a_discard_tells_how_the_master_goes_on_with_times_on_its_clock(test_fmu):
    # After a discarded step the instance is in the step-failed state, where fmi2DoStep is refused.
    # The message at a step limit said that "the next advance goes on from it" (the simulation's
    # words for its own callers) and gave the times on the simulation's clock, t - start: at a start
    # time of 100 s, "at t = 1.8e-05 s while advancing to 1 s" beside "stopped at 100.000018". It
    # now names the limit the master sets and the ways on; every time in it is the FMU's, between
    # the step's ends.
    inst = Instance(test_fmu("driven_oscillator")).start({"solver.max_steps": 2, "solver.rtol": 1e-10},
                                                         start_time=100.0)
    s = inst.slave
    try:
        with pytest.raises(FMICallException):
            s.doStep(100.0, 1.0)
        reached = s.getRealStatus(2)  # fmi2LastSuccessfulTime
        (text,) = [m[2] for m in inst.messages if m[1] == "logStatusDiscard"]
        assert "goes on from it" not in text, text
        assert "solver.max_steps" in text and "fmi2SetFMUstate" in text, text
        times = [x for x in numbers_in(text) if x != 2]  # 2: the internal steps allowed
        assert reached in times and all(100.0 <= x <= 101.0 for x in times), text
        assert "fmi2DoStep: the step from 100 to 101 stopped at " in text, text
        expect_error(inst, lambda: s.doStep(reached, 0.1), "illegal call sequence")
    finally:
        inst.free()


def test_a_discard_names_the_clock_of_the_solvers_report(test_fmu):
    # Any other failure is told in the solver's report, whose times run on the simulation's clock:
    # the message names its origin, the start time, so that the step's end there (1e300 N make the
    # forces overflow at once) is the step's end on the FMU's clock less that start time.
    inst = Instance(test_fmu("driven_oscillator")).start(start_time=100.0)
    s = inst.slave
    try:
        s.doStep(100.0, 0.25)
        inst.set("tip.fx", 1e300)
        with pytest.raises(FMICallException):
            s.doStep(100.25, 0.25)
        (text,) = [m[2] for m in inst.messages if m[1] == "logStatusDiscard"]
        report = text[text.index("The solver's report"):]
        assert "start time 100 s" in report, text
        advancing = float(re.search(r"while advancing to (\S+) s", report).group(1))
        # The simulation's time is t - start, as it rounds: 100.5 - 100 exactly.
        assert advancing == 100.5 - 100.0, text
    finally:
        inst.free()


def test_parameters_in_the_simulation_settings_set_the_solver(test_fmu):
    # param_settings: "rtol": "tol", "max_steps": "ms" in the file's settings. Setting tol and ms
    # is setting solver.rtol and solver.max_steps (so tol wins over the experiment's tolerance, as
    # solver.rtol does); the solver variables read the values, and ms = 2 makes the 1 s step fail
    # as solver.max_steps = 2 does above. Both are fixed parameters. A reset goes back to the file.
    # Of tol and solver.rtol, the one changed last counts: tol set to the value it has changes
    # nothing, so an importer that writes every start value after the user's solver.rtol leaves
    # it alone.
    inst = Instance(test_fmu("param_settings"))
    s = inst.slave
    max_steps = inst.vr["solver.max_steps"]
    try:
        assert inst.variables["tol"].variability == inst.variables["ms"].variability == "fixed"
        s.setupExperiment(tolerance=1e-4, startTime=0.0)
        s.enterInitializationMode()
        inst.set("tol", 1e-10)
        inst.set("ms", 2)
        s.exitInitializationMode()
        assert inst.get("solver.rtol") == 1e-10 and s.getInteger([max_steps]) == [2]
        expect_error(inst, lambda: inst.set("ms", 3), "ms", "fixed parameter")
        with pytest.raises(FMICallException) as info:
            s.doStep(0.0, 1.0)
        assert info.value.status == 2  # fmi2Discard
        s.reset()
        inst.start()
        assert inst.get("solver.rtol") == 1e-6 and s.getInteger([max_steps]) == [100000]
        s.doStep(0.0, 1.0)
        s.reset()
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        inst.set("solver.rtol", 1e-9)
        inst.set("tol", 1e-6)  # its start value
        assert inst.get("solver.rtol", "tol") == [1e-9, 1e-6]
        inst.set("tol", 1e-8)
        assert inst.get("solver.rtol", "tol") == [1e-8, 1e-8]
        s.exitInitializationMode()
    finally:
        inst.free()


def test_parameters_in_the_simulation_settings_set_every_numeric_solver_setting(package, tmp_path):
    # docs/fmu.md: setting a parameter that the file's "simulation" object names is setting its
    # solver variable. Beside rtol and max_steps (above), the absolute tolerances and the step
    # limit: a run whose parameters loosen atol_position and atol_velocity to 1e-2 and limit the step
    # to 0.05 s is the run with the solver variables set so, bit for bit (the same settings make
    # the same steps), and the solver variables read the values; the loose tolerances make another
    # run than the file's defaults (velocities of about 1 m/s, rtol 1e-6: the absolute tolerances
    # decide the steps), so the comparison is not one of runs that the settings leave alike.
    model = json.loads((MODELS / "param_settings.json").read_text())
    model["parameters"].update({"ap": 1e-8, "av": 1e-6, "hs": 0.0})
    model["simulation"].update({"atol_position": "ap", "atol_velocity": "av", "max_step": "hs"})
    path = tmp_path / "solver_parameters.json"
    path.write_text(json.dumps(model))
    fmu = package(path)
    settings = {"ap": 1e-2, "av": 1e-2, "hs": 0.05}
    solver = {"solver.atol_position": 1e-2, "solver.atol_velocity": 1e-2, "solver.max_step": 0.05}
    runs = []
    for start in (settings, solver, {}):
        inst = Instance(fmu).start(start)
        try:
            if start:
                assert inst.get(*solver) == list(solver.values()), start
            for n in range(10):
                inst.slave.doStep(0.1 * n, 0.1)
            runs.append(inst.get("tip.x", "tip.vx", "base.fx"))
        finally:
            inst.free()
    assert runs[0] == runs[1] and runs[1] != runs[2], runs


def test_reset_equals_a_fresh_instance(test_fmu):
    fmu = test_fmu("driven_oscillator")
    a = Instance(fmu, "a")
    b = Instance(fmu, "b")
    try:
        a.start({"k": 80.0, "tip.fx": 1.0})
        for n in range(10):
            a.slave.doStep(0.05 * n, 0.05)
        a.slave.reset()
        a.start()
        b.start()
        for n in range(20):
            a.slave.doStep(0.05 * n, 0.05)
            b.slave.doStep(0.05 * n, 0.05)
            names = ["tip.x", "tip.vx", "base.fx", "energy.kinetic", "energy.elastic"]
            assert a.get(*names) == b.get(*names)
        assert a.get("k") == 50.0
    finally:
        a.free()
        b.free()


def instantiates_at(fmu, folder, location):
    """Whether the FMU, unpacked in folder and loaded afresh, instantiates with the resource location
    given (the instance is freed again), and its log."""
    inst = Instance(fmu, unzipdir=str(folder), instantiate=False)
    try:
        comp = inst.slave.fmi2Instantiate(b"uri", 1, inst.md.guid.encode(), location.encode(), inst.callbacks, 0, 0)
        if comp:
            inst.slave.fmi2FreeInstance(comp)
        return bool(comp), inst.log_text()
    finally:
        inst.slave.freeLibrary()


def test_resource_uri_forms_and_spaces(test_fmu, tmp_path):
    # The resources folder in a path with a space, passed as file:/ (one slash) and with %20, and
    # as a plain path that contains "://" (a folder "a:" and a doubled slash), which is no scheme.
    import shutil
    from fmpy import extract
    folder = tmp_path / "with space" / "a:"
    extract(str(test_fmu("driven_oscillator")), unzipdir=str(folder))
    # Scheme and host in any case (RFC 3986 3.1, 3.2.2).
    for uri in (f"file:{folder}/resources", f"file://{str(folder).replace(' ', '%20')}/resources/",
                f"file://localhost{str(folder).replace(' ', '%20')}/resources", f"{folder}//resources",
                f"FILE://{folder}/resources", f"File:{folder}/resources",
                f"file://LOCALHOST{folder}/resources", f"FILE://LocalHost{folder}/resources"):
        ok, log = instantiates_at(test_fmu("driven_oscillator"), folder, uri)
        assert ok, (uri, log)
    shutil.rmtree(folder)


def test_percent_escapes_take_hex_letters_in_either_case(test_fmu, tmp_path):
    # A folder named "café" is "caf%C3%A9" in a file URI (RFC 3986 2.1: hex digits in either
    # case, the same octets), so both spellings name it.
    from fmpy import extract
    fmu = test_fmu("driven_oscillator")
    folder = tmp_path / "café"
    extract(str(fmu), unzipdir=str(folder))
    upper = (folder / "resources").as_uri()
    assert "%C3%A9" in upper
    for uri in (upper, upper.replace("%C3%A9", "%c3%a9"), upper.replace("%C3%A9", "%C3%a9")):
        ok, log = instantiates_at(fmu, folder, uri)
        assert ok, (uri, log)


def test_a_percent_escape_at_the_end_of_a_file_uri_is_decoded(test_fmu, tmp_path):
    # "%73" is "s" (RFC 3986 2.3: an escaped unreserved character is the character), also as the
    # last three characters of the URI, with or without a trailing slash after them.
    from fmpy import extract
    fmu = test_fmu("driven_oscillator")
    extract(str(fmu), unzipdir=str(tmp_path))
    uri = (tmp_path / "resources").as_uri()
    assert uri.endswith("/resources")
    for location in (uri[:-1] + "%73", uri[:-1] + "%73/", uri[:-2] + "%65%73"):
        inst = Instance(fmu, unzipdir=str(tmp_path), instantiate=False)
        try:
            comp = inst.slave.fmi2Instantiate(b"uri", 1, inst.md.guid.encode(), location.encode(), inst.callbacks, 0, 0)
            assert comp, (location, inst.log_text())
            inst.slave.fmi2FreeInstance(comp)
        finally:
            inst.slave.freeLibrary()


def test_a_plain_path_is_taken_as_it_is(test_fmu, tmp_path):
    # A plain path escapes nothing: a folder named "50%41" (or "a%25b") is that folder, which a
    # plain path names as it is and a file URI with its '%' escaped as "%25". Decoded, the plain
    # path named the folders "50A" and "a%b", which do not exist.
    from fmpy import extract
    fmu = test_fmu("driven_oscillator")
    for name in ("50%41", "a%25b"):
        folder = tmp_path / name
        extract(str(fmu), unzipdir=str(folder))
        resources = folder / "resources"
        for location in (str(resources), f"{resources}/", resources.as_uri()):
            ok, log = instantiates_at(fmu, folder, location)
            assert ok, (location, log)


def test_a_rejected_set_real_changes_nothing(test_fmu):
    # One value of a call rejected: none of the others is taken, in every state where values can be
    # set. Running on gives bit for bit what an instance that never saw the call gives (a tunable
    # parameter taken and put back would have restarted the solver).
    fmu = test_fmu("driven_oscillator")
    inst, reference = Instance(fmu, "a"), Instance(fmu, "b")
    s, vr = inst.slave, inst.vr
    names = ["solver.rtol", "k", "tip.fx", "base.x"]
    try:
        s.setupExperiment(startTime=0.0)
        expect_error(inst, lambda: s.setReal([vr[n] for n in names] + [vr["solver.atol_position"]],
                                             [1e-8, 70.0, 1.0, 0.1, -1.0]), "solver.atol_position = -1")
        s.enterInitializationMode()
        expect_error(inst, lambda: s.setReal([vr[n] for n in names] + [vr["m"]], [1e-8, 70.0, 1.0, 0.1, -1.0]),
                     "m = -1")
        s.exitInitializationMode()
        reference.start()
        assert inst.get(*names) == reference.get(*names)
        for n in range(5):
            s.doStep(0.02 * n, 0.02)
            reference.slave.doStep(0.02 * n, 0.02)
        expect_error(inst, lambda: s.setReal([vr["k"], vr["tip.fx"], vr["d"]], [70.0, 1.0, -1.0]), "d = -1")
        expect_error(inst, lambda: s.setReal([vr["k"], vr["tip.fx"], vr["solver.rtol"]], [70.0, 1.0, 1e-3]),
                     "fixed parameter")
        for n in range(5, 20):
            s.doStep(0.02 * n, 0.02)
            reference.slave.doStep(0.02 * n, 0.02)
            assert inst.get("tip.x", "tip.vx", "base.fx") == reference.get("tip.x", "tip.vx", "base.fx")
        assert inst.get("k", "d", "tip.fx") == [50.0, 0.0, 0.0]
    finally:
        inst.free()
        reference.free()



def test_a_rejected_set_real_puts_the_parameters_back_in_reverse_order(test_fmu):
    # xa = xb is refused (the spring's rest length would be 0). xa = 5 then xb = 0 are both valid
    # steps, k = -1 is not: putting xa back first would pass through xa = xb = 0, which the model
    # refuses, and leave xa at 5; undone last first, every step back is one taken on the way.
    inst = Instance(test_fmu("two_ends"))
    s, vr = inst.slave, inst.vr
    try:
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        expect_error(inst, lambda: s.setReal([vr["xa"], vr["xb"], vr["k"]], [5.0, 0.0, -1.0]), "k = -1")
        assert inst.get("xa", "xb", "k") == [0.0, 1.0, 50.0]
        s.exitInitializationMode()
        s.doStep(0.0, 0.1)
        assert inst.get("p[1].x") == 1.0
    finally:
        inst.free()


def test_parameters_that_set_the_structure_are_constants_of_the_packaged_fmu(test_fmu):
    # rope_n: n is the rope's segment count. p[i].x and the ports name particles by index, and the
    # instance's buffers are sized at instantiation, so n = 4 is part of the FMU: n is declared a
    # constant (causality local), and another value, larger (writes past the buffers) or smaller
    # (reads past the simulation's arrays), is refused with the way to get such an FMU, in every
    # state and in a state written by something else; the instance steps on as before.
    fmu = test_fmu("rope_n")
    assert validate_fmu(str(fmu)) == []
    n, e = (next(v for v in read_model_description(str(fmu)).modelVariables if v.name == name) for name in "nE")
    assert (n.causality, n.variability, n.initial, n.start) == ("local", "constant", "exact", "4")
    assert (e.causality, e.variability) == ("parameter", "tunable")
    inst = Instance(fmu)
    s = inst.slave
    try:
        s.setupExperiment(startTime=0.0)
        expect_error(inst, lambda: inst.set("n", 400), "n = 400 refused", "springmass fmu")
        s.enterInitializationMode()
        expect_error(inst, lambda: inst.set("n", 2), "n = 2 refused", "springmass fmu")
        inst.set("n", 4)  # its own value: an importer may pass every start value
        s.exitInitializationMode()
        expect_error(inst, lambda: inst.set("n", 5), "n = 5 refused")
        s.doStep(0.0, 0.01)
        blob = s.serializeFMUstate(s.getFMUstate())
        params = blob.index(struct.pack("<dd", 4.0, 100.0)) // 8  # n and E, in file order
        bad = bytearray(blob)
        bad[8 * params:8 * params + 8] = struct.pack("<d", 400.0)
        h = 0xcbf29ce484222325  # the checksum made valid again (test_fmu_state.checksummed)
        for i, byte in enumerate(bad):
            if not 56 <= i < 64:
                h = ((h ^ byte) * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
        bad[56:64] = struct.pack("<Q", h)
        before = inst.get("hook.fx", "tip.x", "p[4].z")
        expect_error(inst, lambda: s.setFMUstate(s.deSerializeFMUstate(bytes(bad))), "n = 400",
                     "sets the model's structure (4 in this FMU)", "springmass fmu", "--set n=400")
        assert inst.get("hook.fx", "tip.x", "p[4].z") == before and inst.get("n") == 4.0
        s.doStep(0.01, 0.01)
        assert math.isfinite(inst.get("hook.fx"))
    finally:
        inst.free()


def test_a_parameter_that_moves_a_port_to_another_particle_is_refused(test_fmu):
    # two_ropes: n segments of rope A come before rope B, whose end is the probe port: n = 10 would
    # put the port's particle index at 14 (at another particle of the FMU's 13, or past them).
    inst = Instance(test_fmu("two_ropes"))
    s = inst.slave
    try:
        assert inst.variables["n"].variability == "constant"
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        for value in (4, 10):
            expect_error(inst, lambda: inst.set("n", value), f"n = {value} refused")
        s.exitInitializationMode()
        assert inst.get("end.x", "end.y", "end.z") == [0.0, 6.0, 0.0]
    finally:
        inst.free()


def test_status_queries_with_null_pointers_and_unknown_kinds(test_fmu):
    inst = Instance(test_fmu("driven_oscillator")).start()
    s = inst.slave
    try:
        for function in (s.fmi2GetStatus, s.fmi2GetRealStatus, s.fmi2GetBooleanStatus, s.fmi2GetStringStatus):
            expect_error(inst, lambda: function(s.component, 0, None), "NULL value")
        expect_error(inst, lambda: s.getStatus(99), "status kind 99", "not an fmi2StatusKind")
        # A kind the function does not deliver is discarded (FMI 2.0, 4.2.3), not refused.
        for call, words in ((lambda: s.getRealStatus(0), ("status kind 0", "fmi2GetStatus")),
                            (lambda: s.getIntegerStatus(2), ("status kind 2", "fmi2GetRealStatus"))):
            before = len(inst.messages)
            with pytest.raises(FMICallException) as info:
                call()
            assert info.value.status == 2  # fmi2Discard
            assert [m[1] for m in inst.messages[before:]] == ["logStatusDiscard"]
            assert all(word in inst.messages[-1][2] for word in words), inst.messages[-1][2]
        assert s.getRealStatus(2) == 0.0  # fmi2LastSuccessfulTime
        assert s.getStatus(0) == 0  # fmi2DoStepStatus: fmi2OK
        assert s.getBooleanStatus(3) == 0  # fmi2Terminated: false
        s.doStep(0.0, 0.1)
    finally:
        inst.free()


def test_inquiry_and_string_and_integer_variables_read_back(test_fmu):
    # The inquiry functions name FMI 2.0 and the default platform; the solver's String and Integer
    # parameters read back what was set, take effect (Adams with fixed-point iteration uses no
    # linear solver and takes more steps), and the pending-status string is empty.
    inst = Instance(test_fmu("driven_oscillator"))
    s = inst.slave
    try:
        assert s.getVersion() == "2.0" and s.getTypesPlatform() == "default"
        vr = inst.vr
        strings = [vr["solver.method"], vr["solver.linear_solver"], vr["solver.jacobian"]]

        def read():
            return [x.decode() if isinstance(x, bytes) else x for x in s.getString(strings)]

        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()  # values are readable from here on (FMI 2.0, 4.2.4)
        assert read() == ["bdf", "auto", "exact"]
        s.setString(strings, ["adams", "klu", "definite"])
        s.setInteger([vr["solver.max_steps"]], [7])
        s.exitInitializationMode()
        assert read() == ["adams", "klu", "definite"]
        assert s.getInteger([vr["solver.max_steps"]]) == [7]
        # 7 internal steps of Adams cannot cover 1 s of the oscillation: discarded, as the
        # setting says.
        with pytest.raises(FMICallException) as info:
            s.doStep(0.0, 1.0)
        assert info.value.status == 2
        assert s.getStringStatus(1) in ("", b"")  # fmi2PendingStatus: nothing pending
    finally:
        inst.free()


def test_extreme_inputs_end_in_a_prompt_discard_and_the_instance_recovers(test_fmu):
    # 1e300 N on the force port, 1e300 m and 1e300 m/s on the motion port: each step is discarded
    # with a message at once, not after the internal step limit: the solver's report of the step
    # (logSolver) counts no internal step and at most 11 right-hand sides (the first, and one per
    # Newton convergence failure, of which CVODE allows 10 in a step). The instance goes on after
    # restoring a state saved before, or after a reset.
    inst = Instance(test_fmu("driven_oscillator"), logging_on=True).start()
    s = inst.slave
    try:
        s.doStep(0.0, 0.1)
        saved = s.getFMUstate()
        for name in ("tip.fx", "base.x", "base.vx"):
            inst.set(name, 1e300)
            n = len(inst.messages)
            with pytest.raises(FMICallException) as info:
                s.doStep(0.1, 0.1)
            assert info.value.status == 2  # fmi2Discard
            assert any(m[1] == "logStatusDiscard" for m in inst.messages[n:])
            report = [m[2] for m in inst.messages[n:] if m[1] == "logSolver"]
            counts = re.match(r"step [^:]*: (\d+) internal steps, (\d+) right-hand sides", report[-1])
            steps, rhs = map(int, counts.groups())
            assert steps == 0 and 1 <= rhs <= 11
            s.setFMUstate(saved)
            inst.set(name, 0.0)
            s.doStep(0.1, 0.1)
            s.setFMUstate(saved)
        inst.set("tip.fx", 1e300)
        with pytest.raises(FMICallException):
            s.doStep(0.1, 0.1)
        s.reset()
        inst.start()
        s.doStep(0.0, 0.1)
        assert math.isfinite(inst.get("tip.x"))
        s.freeFMUstate(saved)
    finally:
        inst.free()


def test_steps_up_to_a_negative_stop_time_and_beyond_the_largest_time(test_fmu):
    # A step that ends exactly at a negative stop time is taken (the stop time's round-off margin
    # was applied as a factor, which tightens it below zero); a step whose end overflows is an
    # fmi2Error that changes nothing, not a discarded step.
    fmu = test_fmu("driven_oscillator")
    inst = Instance(fmu)
    s = inst.slave
    try:
        s.setupExperiment(startTime=-1001.0, stopTime=-1000.0)
        s.enterInitializationMode()
        s.exitInitializationMode()
        s.doStep(-1001.0, 0.5)
        s.doStep(-1000.5, 0.5)
        assert s.getRealStatus(2) == -1000.0
        expect_error(inst, lambda: s.doStep(-1000.0, 0.5), "goes past the stop time")
        s.reset()
        inst.start(start_time=1e308)
        expect_error(inst, lambda: s.doStep(1e308, 1e308), "largest representable time")
        assert s.getStatus(0) == 0  # fmi2DoStepStatus: still fmi2OK
        assert s.getRealStatus(2) == 1e308
    finally:
        inst.free()


def test_steps_below_the_time_resolution_do_not_pass_the_stop_time(test_fmu):
    # A step shorter than the resolution of the master's clock, 4 eps max(1 s, |t|), is taken with
    # nothing to integrate and moves the FMU's time to t + h. Such steps are held to the stop time
    # as any other: at t = 1 s a step of 8e-16 s moves the time by 2 ulps (4.4e-16 s), so within the
    # stop time's margin of 1000 ulps (2.2e-13 s) about 500 of them are taken, and the next is
    # refused. They were never checked: 100 000 of them carried the time to 1 + 8.9e-11 s, 400
    # margins past the stop time.
    inst = Instance(test_fmu("driven_oscillator")).start(stop_time=1.0)
    s = inst.slave
    try:
        s.doStep(0.0, 1.0)
        margin = 1e3 * sys.float_info.epsilon
        t = 1.0
        for _ in range(1000):
            if t + 8e-16 > 1.0 + margin:
                break
            s.doStep(t, 8e-16)
            t = s.getRealStatus(2)  # fmi2LastSuccessfulTime
        assert 1.0 + margin - 8e-16 < t <= 1.0 + margin
        state = s.getReal([inst.vr["tip.x"], inst.vr["tip.vx"]])
        expect_error(inst, lambda: s.doStep(t, 8e-16), "goes past the stop time")
        assert s.getStatus(0) == 0 and s.getRealStatus(2) == t  # fmi2OK, fmi2LastSuccessfulTime
        assert s.getReal([inst.vr["tip.x"], inst.vr["tip.vx"]]) == state
    finally:
        inst.free()


def test_resource_locations_of_other_hosts_and_schemes_are_refused(test_fmu):
    # file://host/dir names another machine (it was read as the local path //host/dir), http://
    # is no file at all, an escaped NUL would cut the path short at a folder that exists, and
    # "file:resources" is a relative file URI, which names no folder (RFC 8089: the path is absolute).
    inst = Instance(test_fmu("driven_oscillator"), instantiate=False)
    try:
        for uri in ("file://otherhost/resources", "FILE://OtherHost/resources", "http://localhost/resources",
                    f"file://{inst.unzipdir}/resources%00/elsewhere", "file:resources", "File:resources/"):
            n = len(inst.messages)
            comp = inst.slave.fmi2Instantiate(b"uri", 1, inst.md.guid.encode(), uri.encode(), inst.callbacks, 0, 0)
            assert not comp, uri
            assert "not a local file URI" in "\n".join(m[2] for m in inst.messages[n:]), uri
    finally:
        inst.free()


def test_values_set_at_packaging_are_the_constants_and_the_start_after_reset(package):
    # hanging_rope_n packaged with --set n=40 --set E=3000: n is the constant 40 (its own value is
    # accepted, the file's 10 refused with the command that packages it), E starts at 3000, and
    # fmi2Reset goes back to those values, not to the file's.
    inst = Instance(package(MODELS / "hanging_rope_n.json", ("n=40", "E=3000")))
    s = inst.slave
    try:
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        assert inst.get("n", "E") == [40.0, 3000.0]
        inst.set("n", 40)
        expect_error(inst, lambda: inst.set("n", 10), "n = 10 refused", "springmass fmu MODEL -o NAME.fmu --set n=10")
        inst.set("E", 5000.0)
        s.exitInitializationMode()
        s.doStep(0.0, 0.01)
        assert inst.get("p[40].z") < 0.0
        s.reset()
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        assert inst.get("n", "E", "p[40].x", "p[40].z") == [40.0, 3000.0, 1.0, 0.0]
    finally:
        inst.free()


def instantiate_edited(inst, text, guid=None):
    """Instantiates inst's unzipped FMU (made with instantiate=False) anew, its
    resources/parameters.txt replaced by `text` (bytes; None: removed) and the GUID given (by
    default the one that matches the edited resources), and frees what it made. Returns whether
    an instance was made and the messages logged meanwhile."""
    resources = f"{inst.unzipdir}/resources"
    if text is None:
        os.remove(f"{resources}/parameters.txt")
    else:
        with open(f"{resources}/parameters.txt", "wb") as f:
            f.write(text)
    model = open(f"{resources}/model.json", "rb").read()
    guid = guid or (fmu_guid(model) if text is None else fmu_guid(model, text))
    before = len(inst.messages)
    comp = inst.slave.fmi2Instantiate(b"edited", 1, guid.encode(), f"file://{resources}".encode(), inst.callbacks,
                                     0, 0)
    if comp:
        inst.slave.fmi2FreeInstance(comp)
    return comp, "\n".join(m[2] for m in inst.messages[before:])


def test_edited_parameter_values_are_refused_at_instantiation(package):
    # resources/parameters.txt is part of the GUID: edited, removed or added by hand, the FMU is
    # refused as one whose resources changed after packaging. With the GUID made to match, each
    # malformed or inconsistent file is refused naming its line; nothing is ever taken in part.
    fmu = package(MODELS / "hanging_rope_n.json", ("n=40", "E=3000"))
    inst = Instance(fmu, instantiate=False)
    try:
        comp, log = instantiate_edited(inst, b"n=40\nE=3000\n")
        assert comp and log == ""
        comp, log = instantiate_edited(inst, b"n=40\nE=3001\n", guid=inst.md.guid)
        assert not comp and "does not match the model file resources/model.json with its parameter values" in log
        for text, message in [
                (b"n=40\nE=3000\nn=41\n", "parameters.txt:3: parameter n is set again (first on line 1)"),
                (b"n=40\nzz=1\n", 'parameters.txt:2: "zz=1": the model has no parameter named "zz"'),
                (b"n=forty\n", 'parameters.txt:1: "n=forty": the value is not a finite number'),
                (b"n=nan\n", 'parameters.txt:1: "n=nan": the value is not a finite number'),
                (b"n 40\n", 'parameters.txt:1: expected NAME=VALUE, got "n 40"'),
                (b"", "parameters.txt:1: empty"),
                (b"n=0\n", 'parameters.txt:1: "n=0": resources/model.json: structures[0].segments: parameter n = 0'),
                (b"n=\xff\x1b[31m\n", 'parameters.txt:1: "n=\\xff\\x1b[31m": the value is not a finite number')]:
            comp, log = instantiate_edited(inst, text)
            assert not comp and message in log, (text, log)
        comp, log = instantiate_edited(inst, None, guid=inst.md.guid)
        assert not comp and "does not match the model file resources/model.json, whose GUID is" in log
    finally:
        inst.free()


# A rope of two segments from (xa, 0, 0) to (xb, 0, 0), xa = 0 and xb = 1 by default, fixed at its
# start, its springs of stiffness per strain: a rope of no length (xa = xb) is refused.
ROPE_BETWEEN_XA_AND_XB = ('{"springmass": 1, "name": "ends", "parameters": {"xa": 0, "xb": 1}, "structures": '
                          '[{"type": "rope", "name": "r", "start": ["xa", 0, 0], "end": ["xb", 0, 0], "segments": 2, '
                          '"structural": {"strain_stiffness": 100}}], "fixed": ["r[0]"]}')


def test_set_values_are_written_in_an_order_the_model_takes(package, tmp_path):
    # A rope from xa = 0 to xb = 1 with per-strain springs: --set xb=3 --set xa=1 ends at 1..3, but
    # xa = 1 before xb moves would give the rope zero length, which the model refuses. The values
    # are written in the file's order where the model takes them there, after the others where not.
    model = tmp_path / "ends.json"
    model.write_text(ROPE_BETWEEN_XA_AND_XB)
    fmu = package(model, ("xb=3", "xa=1"))
    with zipfile.ZipFile(fmu) as z:
        assert z.read("resources/parameters.txt") == b"xb=3\nxa=1\n"
    # Given the other way round, the order given fails as the file's does (xa first), and a
    # second pass over the file's order takes xa after xb: the same file, whatever the order.
    with zipfile.ZipFile(package(model, ("xa=1", "xb=3"))) as z:
        assert z.read("resources/parameters.txt") == b"xb=3\nxa=1\n"
    inst = Instance(fmu)
    try:
        inst.start()
        assert inst.get("p[0].x", "p[1].x", "p[2].x") == [1.0, 2.0, 3.0]
    finally:
        inst.free()


def test_set_values_the_file_order_cannot_take_keep_the_order_given(package, tmp_path):
    # Two ropes start at (a, b, c) and (a, c, b), from (0, 0, 0), and end at (1, 1, 0) and
    # (1, 5, 0). --set b=1 --set c=5 --set a=1 is taken in that order (each rope keeps a length),
    # but the file's order takes a = 1 first, and then b = 1 would put the first rope's start on
    # its end and c = 5 the second's, in either order: no pass over the file's order takes them
    # all. The order given is written then, and the FMU starts there.
    model = tmp_path / "two_starts.json"
    model.write_text('{"springmass": 1, "name": "two_starts", "parameters": {"a": 0, "b": 0, "c": 0}, '
                     '"structures": [{"type": "rope", "name": "r1", "start": ["a", "b", "c"], "end": [1, 1, 0], '
                     '"segments": 1, "structural": {"strain_stiffness": 10}}, {"type": "rope", "name": "r2", '
                     '"start": ["a", "c", "b"], "end": [1, 5, 0], "segments": 1, '
                     '"structural": {"strain_stiffness": 10}}], "fixed": ["r1[0]", "r2[0]"]}')
    fmu = package(model, ("b=1", "c=5", "a=1"))
    with zipfile.ZipFile(fmu) as z:
        assert z.read("resources/parameters.txt") == b"b=1\nc=5\na=1\n"
    # b set again at the end: where each was last set (c, a, b) a = 1 comes while b = 0, and the
    # order where each was first set is written instead, the same FMU.
    again = package(model, ("b=1", "c=5", "a=1", "b=1"))
    assert read_model_description(str(again)).guid == read_model_description(str(fmu)).guid
    inst = Instance(fmu)
    try:
        inst.start()
        assert inst.get("p[0].x", "p[0].y", "p[0].z", "p[2].y", "p[2].z") == [1.0, 1.0, 5.0, 5.0, 1.0]
    finally:
        inst.free()


def test_set_values_no_order_takes_one_at_a_time_are_taken_together(package, tmp_path):
    # A rope from xa = 0 to xb = 1 turned round: --set xa=1 --set xb=0. Either value alone puts the
    # start on the end (a rope of no length, which its per-strain springs refuse), so no order
    # takes them one at a time; together they are a rope of length 1, as `springmass run --set`
    # takes them. The FMU starts from the rope turned round, its particles at 1, 0.5 and 0 m: the
    # midpoint (xa + xb) / 2 and the ends are exact in binary, so the positions are compared
    # exactly, with those `springmass run --positions` gives at t = 0.
    model = tmp_path / "ends.json"
    model.write_text(ROPE_BETWEEN_XA_AND_XB)
    run = subprocess.run([str(CLI), "run", str(model), "-q", "-o", "-", "--t-end", "0.1", "--positions",
                          "--set", "xa=1", "--set", "xb=0"], capture_output=True, text=True, check=True)
    header, first = run.stdout.splitlines()[:2]
    row = dict(zip(header.split(","), map(float, first.split(","))))
    assert [row[f"particle.r[{i}].x"] for i in range(3)] == [1.0, 0.5, 0.0]
    # They are written in the file's order, whatever the order given: the same FMU either way.
    fmu = package(model, ("xa=1", "xb=0"))
    for sets in (("xa=1", "xb=0"), ("xb=0", "xa=1")):
        with zipfile.ZipFile(package(model, sets)) as z:
            assert z.read("resources/parameters.txt") == b"xa=1\nxb=0\n"
    inst = Instance(fmu)
    try:
        inst.start()
        assert inst.get("p[0].x", "p[1].x", "p[2].x") == [1.0, 0.5, 0.0]
        assert [inst.slave.getReal([inst.vr[n]])[0] for n in ("xa", "xb")] == [1.0, 0.0]
    finally:
        inst.free()


def test_values_taken_together_do_not_pass_over_a_malformed_line_after_them(package, tmp_path):
    # The rope turned round (xa=1, xb=0: either value alone is refused, so they are taken together
    # at the end), its resources/parameters.txt edited to hold a malformed line after the values
    # and the GUID made to match: the file is refused as any malformed one is. Taking the values
    # together does not make the FMU pass over the line. The same file without it is taken.
    model = tmp_path / "ends.json"
    model.write_text(ROPE_BETWEEN_XA_AND_XB)
    inst = Instance(package(model, ("xa=1", "xb=0")), instantiate=False)
    try:
        comp, log = instantiate_edited(inst, b"xa=1\nxb=0\n")
        assert comp and log == ""
        comp, log = instantiate_edited(inst, b"xa=1\nxb=0\nxa 2\n")
        assert not comp and "parameters.txt:" in log, log
    finally:
        inst.free()


def test_an_absolute_tolerance_below_the_bound_is_refused_when_set(test_fmu):
    # Below 1e-150 CVODE's error norm overflows (simulation.h): the value is refused when it is
    # set, not at fmi2ExitInitializationMode; the bound itself is taken through initialisation.
    inst = Instance(test_fmu("driven_oscillator"))
    s, vr = inst.slave, inst.vr
    try:
        s.setupExperiment(startTime=0.0)
        expect_error(inst, lambda: s.setReal([vr["solver.atol_velocity"]], [1e-200]),
                     "solver.atol_velocity = 1e-200 rejected", "at least 1e-150")
        s.setReal([vr["solver.atol_velocity"]], [1e-150])
        s.enterInitializationMode()
        s.exitInitializationMode()
        assert inst.get("solver.atol_velocity") == 1e-150
    finally:
        inst.free()


def test_logging_off_with_categories_leaves_the_others_as_they_were(test_fmu):
    # FMI 2.0 (2.1.5), docs/fmu.md: fmi2SetDebugLogging(fmi2False, categories) switches those
    # categories off and leaves the others as they were, here every category (loggingOn at
    # instantiation). A round makes one message of each of three categories (as in the test above);
    # the event names the one parameter that changed, k, with its new value.
    inst = Instance(test_fmu("driven_oscillator"), logging_on=True).start()
    s = inst.slave

    try:
        assert categories_logged(inst, 0.0) == {"logEvents", "logSolver", "logStatusError"}
        events = [m[2] for m in inst.messages if m[1] == "logEvents"]
        assert len(events) == 1 and "parameter k = 51 " in events[0], events
        s.setDebugLogging(False, ["logSolver"])
        assert categories_logged(inst, 0.1) == {"logEvents", "logStatusError"}
        s.setDebugLogging(False, ["logEvents"])
        assert categories_logged(inst, 0.2) == {"logStatusError"}
    finally:
        inst.free()


def test_directional_derivatives_are_of_outputs_only(test_fmu):
    # FMI 2.0 (fmi2GetDirectionalDerivative): the unknowns are outputs (or states, here the local
    # particle variables); a parameter or an input is no unknown: refused with a message.
    inst = Instance(test_fmu("driven_oscillator")).start()
    s, vr = inst.slave, inst.vr
    try:
        for name in ("k", "tip.fx", "solver.rtol"):
            expect_error(inst, lambda: s.getDirectionalDerivative([vr[name]], [vr["base.x"]], [1.0]), name,
                         "not an output")
        assert s.getDirectionalDerivative([vr["p[0].x"]], [vr["base.x"]], [1.0]) == [1.0]
    finally:
        inst.free()


SETTINGS = {
    "springmass": 1, "name": "settings", "description": "The driven oscillator with every solver setting given.",
    "parameters": {"m": 2.0, "k": 50.0, "tol": 1e-7, "hmax": 0.005},
    "gravity": [0, 0, 0], "mass_damping": 0.0,
    "particles": [{"name": "anchor", "position": [0, 0, 0], "fixed": True},
                  {"name": "bob", "position": [0.7, 0, 0], "mass": "m"}],
    "springs": [{"a": "anchor", "b": "bob", "stiffness": "k", "rest_length": 0.5}],
    "ports": [{"name": "base", "particle": "anchor", "kind": "motion"},
              {"name": "tip", "particle": "bob", "kind": "force"}],
    "simulation": {"stop_time": 3.0, "output_interval": 0.02, "rtol": "tol", "atol_position": 1e-9,
                   "atol_velocity": 1e-7, "max_step": "hmax", "max_steps": 777, "method": "adams", "solver": "klu",
                   "jacobian": "definite", "input_changes": "keep", "stability_limit_detection": False},
    "fmu": {"particle_variables": False}}


def test_a_saved_model_declares_the_units_of_the_original(package, tmp_path):
    # The trampoline's sheet gives its per-section stiffness Y and damping eta per unit width, in
    # N/m and N s/m; its saved form writes them as single springs' constants, whose section may be
    # a width or an area, and keeps the units in "parameter_units": the FMU packaged from the saved
    # file declares the units the original's does.
    saved = tmp_path / "trampoline_saved.json"
    subprocess.run([str(CLI), "statics", str(ROOT / "models" / "trampoline.json"), "-q", "--save-model", str(saved)],
                   check=True, capture_output=True)
    for model in (ROOT / "models" / "trampoline.json", saved):
        md = read_model_description(str(package(model)))
        units = {v.name: v.unit for v in md.modelVariables}
        assert (units["Y"], units["eta"]) == ("N/m", "N.s/m"), model
        base = {u.name: (u.baseUnit.kg, u.baseUnit.m, u.baseUnit.s) for u in md.unitDefinitions}
        assert base["N/m"] == (1, 0, -2) and base["N.s/m"] == (1, 0, -1)


def test_the_description_declares_what_the_fmu_holds(package, tmp_path):
    # modelDescription.xml is written from the table the FMU uses at run time: every parameter's
    # start value (initial="exact") is what the instance reads in initialisation mode, here with
    # every solver setting of the file away from its default; the DefaultExperiment is the file's
    # stop time, output interval and tolerance; "particle_variables": false leaves out the
    # particles' variables; the units are the SI units they name, the model file's parameters' those
    # of the values they stand for.
    model = tmp_path / "settings.json"
    model.write_text(json.dumps(SETTINGS))
    fmu = package(model)
    md = read_model_description(str(fmu))
    experiment = md.defaultExperiment
    assert [float(experiment.stopTime), float(experiment.stepSize), float(experiment.tolerance)] == [3.0, 0.02, 1e-7]
    assert not [v.name for v in md.modelVariables if v.name.startswith("p[")]
    base = {u.name: (u.baseUnit.kg, u.baseUnit.m, u.baseUnit.s) for u in md.unitDefinitions}
    assert base == {"m": (0, 1, 0), "m/s": (0, 1, -1), "N": (1, 1, -2), "J": (1, 2, -2), "s": (0, 0, 1),
                    "1": (0, 0, 0), "kg": (1, 0, 0), "N/m": (1, 0, -2)}
    units = {v.name: v.unit for v in md.modelVariables}
    assert [units[name] for name in ("m", "k", "tol", "hmax")] == ["kg", "N/m", "1", "s"]
    inst = Instance(fmu)
    s = inst.slave
    try:
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        parameters = [v for v in md.modelVariables if v.causality == "parameter"]
        assert {v.name for v in parameters} >= {"solver.max_step", "solver.max_steps", "solver.method", "hmax",
                                                "solver.input_changes", "solver.stability_limit_detection"}
        for v in parameters:
            if v.type == "Real":
                value, start = s.getReal([v.valueReference])[0], float(v.start)
            elif v.type == "Integer":
                value, start = s.getInteger([v.valueReference])[0], int(v.start)
            elif v.type == "Boolean":
                value, start = s.getBoolean([v.valueReference])[0], v.start == "true"
            else:
                value, start = s.getString([v.valueReference])[0], v.start
                value = value.decode() if isinstance(value, bytes) else value
            assert value == start, (v.name, value, start)
    finally:
        inst.free()


def test_settings_named_by_parameters_are_explicit_solver_settings(package, tmp_path):
    # "rtol": "tol" and "max_step": "hmax": setting tol is setting solver.rtol, so that the
    # experiment's tolerance, given after it, leaves it alone (as after solver.rtol itself); hmax
    # sets solver.max_step, and 1 ms with 50 internal steps allowed cannot cover a step of 0.1 s
    # (at least 100 internal steps): discarded.
    model = tmp_path / "settings.json"
    model.write_text(json.dumps(SETTINGS))
    inst = Instance(package(model))
    s = inst.slave
    try:
        inst.set("tol", 1e-9)
        s.setupExperiment(tolerance=1e-3, startTime=0.0)
        s.enterInitializationMode()
        inst.set("hmax", 1e-3)
        inst.set("solver.max_steps", 50)
        assert inst.get("solver.rtol", "solver.max_step") == [1e-9, 1e-3]
        s.exitInitializationMode()
        with pytest.raises(FMICallException) as info:
            s.doStep(0.0, 0.1)
        assert info.value.status == 2  # fmi2Discard
    finally:
        inst.free()


def test_a_max_step_set_after_an_output_was_read_in_initialisation_mode_is_taken(test_fmu):
    # Reading an output in initialisation mode makes the simulation; a solver.max_step set after
    # it still limits the steps: 1 ms with 50 internal steps allowed cannot cover a step of 0.1 s
    # (at least 100 internal steps): discarded. Unlimited, 50 steps cover it.
    for max_step, discarded in ((0.0, False), (1e-3, True)):
        inst = Instance(test_fmu("driven_oscillator"))
        s = inst.slave
        try:
            s.setupExperiment(startTime=0.0)
            s.enterInitializationMode()
            inst.set("solver.max_steps", 50)
            inst.get("base.fx")  # an output: the simulation is made
            inst.set("solver.max_step", max_step)
            s.exitInitializationMode()
            if discarded:
                with pytest.raises(FMICallException) as info:
                    s.doStep(0.0, 0.1)
                assert info.value.status == 2  # fmi2Discard
            else:
                s.doStep(0.0, 0.1)
        finally:
            inst.free()


@pytest.mark.parametrize("name, value", [("solver.rtol", 1e-3), ("solver.atol_position", 1e-2),
                                         ("solver.atol_velocity", 1e-2), ("solver.max_step", 1e-3)])
def test_a_solver_setting_set_after_an_output_was_read_in_initialisation_mode_is_taken(test_fmu, name, value):
    # Reading an output in initialisation mode makes the simulation; a solver setting set after it
    # gives the run of the same setting set before any output was read, to the bit, and not the run
    # of the default (the setting has an effect on this run: its result differs).
    def run(read_first, setting):
        inst = Instance(test_fmu("driven_oscillator"))
        s = inst.slave
        try:
            s.setupExperiment(startTime=0.0)
            s.enterInitializationMode()
            if read_first:
                inst.get("base.fx")  # an output: the simulation is made
            if setting:
                inst.set(name, value)
            s.exitInitializationMode()
            for k in range(10):
                s.doStep(0.1 * k, 0.1)
            return inst.get("base.fx", "energy.dissipated")
        finally:
            inst.free()

    assert run(True, True) == run(False, True) != run(False, False)


def test_a_step_that_ends_before_the_fmus_time_is_refused(test_fmu):
    # The communication point is taken within 1000 ulps of the FMU's time, so it may lag it by more
    # than a short step: that step would end before the FMU's time. It is an fmi2Error that changes
    # nothing; it was a discard that left the instance unable to step, reporting a last successful
    # time after the step's end. With and without a stop time (two ways of advancing).
    for stop_time in (None, 5.0):
        inst = Instance(test_fmu("driven_oscillator")).start(stop_time=stop_time)
        s = inst.slave
        try:
            t = 0.0
            for _ in range(100):
                s.doStep(t, 0.01)
                t += 0.01
            assert t != 1.0  # 1.0000000000000007: the sum of a hundred 0.01 s
            lagging = t
            for _ in range(100):
                lagging = math.nextafter(lagging, 0.0)
            state = s.getReal([inst.vr["tip.x"], inst.vr["tip.vx"]])
            expect_error(inst, lambda: s.doStep(lagging, 1e-15), "not after the FMU's time")
            assert lagging + (t - lagging) == t  # a step that ends exactly at the FMU's time
            expect_error(inst, lambda: s.doStep(lagging, t - lagging), "not after the FMU's time")
            assert s.getStatus(0) == 0 and s.getRealStatus(2) == t  # fmi2OK, fmi2LastSuccessfulTime
            assert s.getReal([inst.vr["tip.x"], inst.vr["tip.vx"]]) == state
            s.doStep(lagging, 0.01)  # a step that does end after it is taken from the lagging point
            assert s.getRealStatus(2) == lagging + 0.01
        finally:
            inst.free()


def test_an_empty_resource_location_is_refused(test_fmu):
    # An empty location names no folder; joined with the file names it read /model.json.
    inst = Instance(test_fmu("driven_oscillator"), instantiate=False)
    try:
        comp = inst.slave.fmi2Instantiate(b"empty", 1, inst.md.guid.encode(), b"", inst.callbacks, 0, 0)
        assert not comp and "missing resource location" in inst.log_text()
    finally:
        inst.free()


def test_instances_of_one_unzipped_fmu_are_freed_independently(test_fmu, tmp_path):
    # Two instances loaded from one folder share the FMU's library: freeing one leaves the other
    # stepping, with the results of an instance alone.
    from fmpy import extract
    folder = extract(str(test_fmu("driven_oscillator")), unzipdir=str(tmp_path / "fmu"))
    alone = Instance(test_fmu("driven_oscillator")).start()
    a = Instance(test_fmu("driven_oscillator"), name="a", unzipdir=folder).start()
    b = Instance(test_fmu("driven_oscillator"), name="b", unzipdir=folder).start()
    try:
        for k in range(10):
            a.slave.doStep(0.01 * k, 0.01)
            b.slave.doStep(0.01 * k, 0.01)
            alone.slave.doStep(0.01 * k, 0.01)
        a.free()
        for k in range(10, 20):
            b.slave.doStep(0.01 * k, 0.01)
            alone.slave.doStep(0.01 * k, 0.01)
        assert b.get("tip.x", "tip.vx") == alone.get("tip.x", "tip.vx")
    finally:
        b.free()
        alone.free()


REFERENCE_ONLY = {
    "springmass": 1, "name": "reference_only",
    "description": "j names the particle of the probe port and nothing else.",
    "parameters": {"j": 2},
    "gravity": [0, 0, -9.81],
    "structures": [{"type": "rope", "name": "rope", "start": [0, 0, 0], "end": [3, 0, 0], "segments": 3,
                    "mass": 0.3, "structural": {"strain_stiffness": 100}}],
    "fixed": ["rope[0]"],
    "ports": [{"name": "probe", "particle": "rope[j]", "kind": "probe"}]}


def test_a_parameter_that_only_names_a_particle_is_a_constant(package, tmp_path):
    # docs/model-format.md, docs/fmu.md: a parameter that feeds a particle reference (here only
    # the index of the probe port's particle, no count) is a constant of the packaged FMU: causality
    # local, variability constant, initial exact; another value is refused with the way to package
    # one, its own value is taken.
    model = tmp_path / "reference_only.json"
    model.write_text(json.dumps(REFERENCE_ONLY))
    fmu = package(model)
    j = next(v for v in read_model_description(str(fmu)).modelVariables if v.name == "j")
    assert (j.causality, j.variability, j.initial, j.start) == ("local", "constant", "exact", "2")
    inst = Instance(fmu)
    s = inst.slave
    try:
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        expect_error(inst, lambda: inst.set("j", 3), "j = 3 refused", "springmass fmu")
        inst.set("j", 2)
        s.exitInitializationMode()
        assert inst.get("probe.x") == 2.0
    finally:
        inst.free()


def test_a_constant_set_to_its_value_keeps_it_to_the_sign_of_a_zero(package, tmp_path):
    # A constant set to its own value is taken and changes nothing (docs/fmu.md); -0 equals 0 and
    # is taken for a constant of 0 too, which keeps its packaged +0: the model's parameters, which
    # tell -0 from 0, are not given it.
    model = tmp_path / "reference_zero.json"
    model.write_text(json.dumps(dict(REFERENCE_ONLY, parameters={"j": 0})))
    inst = Instance(package(model))
    s = inst.slave
    try:
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        inst.set("j", -0.0)
        s.exitInitializationMode()
        assert math.copysign(1.0, inst.get("j")) == 1.0
        s.doStep(0.0, 0.01)
        inst.set("j", -0.0)
        assert math.copysign(1.0, inst.get("j")) == 1.0
    finally:
        inst.free()
    # Also in a call that changes a parameter beside it, which rebuilds the model from the values set.
    stiff = dict(REFERENCE_ONLY, parameters={"j": 0, "k": 100})
    stiff["structures"] = [dict(REFERENCE_ONLY["structures"][0], structural={"strain_stiffness": "k"})]
    model = tmp_path / "reference_zero_stiffness.json"
    model.write_text(json.dumps(stiff))
    inst = Instance(package(model))
    s = inst.slave
    try:
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        s.setReal([inst.variables["j"].valueReference, inst.variables["k"].valueReference], [-0.0, 120.0])
        s.exitInitializationMode()
        assert math.copysign(1.0, inst.get("j")) == 1.0 and inst.get("k") == 120.0
    finally:
        inst.free()


def test_setup_without_a_tolerance_takes_the_files_after_one_with(test_fmu):
    # fmi2SetupExperiment may be called again before initialisation: without a tolerance the
    # second call leaves the file's relative tolerance (driven_oscillator.json names none: the
    # default 1e-6), not the first call's 1e-3.
    inst = Instance(test_fmu("driven_oscillator"))
    s = inst.slave
    try:
        s.setupExperiment(tolerance=1e-3, startTime=0.0)
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        assert inst.get("solver.rtol") == 1e-6
        s.exitInitializationMode()
    finally:
        inst.free()


def test_input_derivatives_of_inputs_only_of_order_one_and_up_and_finite(test_fmu):
    # Each refusal is an fmi2Error naming the variable and changes nothing: the run that follows
    # is that of no call. Orders above 1 and a motion port's position derivative are taken and not
    # used (noted under logEvents).
    inst = Instance(test_fmu("driven_oscillator"), logging_on=True).start()
    plain = Instance(test_fmu("driven_oscillator")).start()
    try:
        s, vr = inst.slave, inst.vr
        expect_error(inst, lambda: s.setRealInputDerivatives([vr["tip.fx"]], [0], [1.0]), "order 0 of tip.fx")
        expect_error(inst, lambda: s.setRealInputDerivatives([vr["tip.fx"]], [1], [math.nan]),
                     "derivative of tip.fx must be finite")
        expect_error(inst, lambda: s.setRealInputDerivatives([vr["tip.x"]], [1], [1.0]), "tip.x is not an input")
        expect_error(inst, lambda: s.setRealInputDerivatives([vr["k"]], [1], [1.0]), "k is not an input")
        expect_error(inst, lambda: s.setRealInputDerivatives([9999], [1], [1.0]), "unknown value reference 9999")
        # All or nothing: a good derivative beside a bad one is not taken either.
        expect_error(inst, lambda: s.setRealInputDerivatives([vr["tip.fx"], vr["tip.y"]], [1, 1], [5.0, 1.0]),
                     "tip.y is not an input")
        before = len(inst.messages)
        s.setRealInputDerivatives([vr["tip.fx"], vr["base.x"]], [2, 1], [5.0, 1.0])
        notes = [m for m in inst.messages[before:]]
        assert len(notes) == 2 and all(m[1] == "logEvents" for m in notes), notes
        assert "order 2 of tip.fx is not used" in notes[0][2] and "base.x is not used" in notes[1][2]
        for n in range(5):
            s.doStep(n * 0.1, 0.1)
            plain.slave.doStep(n * 0.1, 0.1)
        assert inst.get("tip.x", "tip.vx") == plain.get("tip.x", "tip.vx")
        # Not after termination, as fmi2SetReal.
        s.terminate()
        expect_error(inst, lambda: s.setRealInputDerivatives([vr["tip.fx"]], [1], [1.0]), "illegal call sequence")
    finally:
        inst.free()
        plain.free()
