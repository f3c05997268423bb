"""The FMU against physics: closed forms, scaling laws and statics, through fmpy."""
import ctypes
import json
import math
import os
import re
import subprocess
import zipfile

import numpy as np
import pytest
import scipy.special
from fmpy import read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException

from conftest import BUNDLED_FMUS, CLI, MODELS, ROOT, undamped_response_to_held_forces
from fmu_helpers import Instance

# driven_oscillator.json: bob of mass m = 2 kg on a spring k = 50 N/m, rest length 0.5 m,
# anchor (motion port "base") held at the origin, bob (force port "tip") released at x = 0.7 m.
M, K, L0, X0 = 2.0, 50.0, 0.5, 0.7


def central_difference(slave, unknown, known, x, seed, h=1e-6):
    """(outputs at x + h seed - outputs at x - h seed) / 2h: the derivative of the unknowns along
    seed, with the knowns put back to x afterwards."""
    slave.setReal(known, list(x + h * seed))
    up = np.array(slave.getReal(unknown))
    slave.setReal(known, list(x - h * seed))
    down = np.array(slave.getReal(unknown))
    slave.setReal(known, list(x))
    return (up - down) / (2 * h)


def test_oscillator_matches_closed_form(test_fmu):
    # Undamped: x(t) = l0 + (x0 - l0) cos(w t), w = sqrt(k/m). rtol 1e-10 in CVODE keeps the
    # global error over 2 s (about 3 periods) far below 1e-6 m.
    r = simulate_fmu(str(test_fmu("driven_oscillator")), stop_time=2.0, output_interval=0.01,
                     start_values={"solver.rtol": 1e-10, "solver.atol_position": 1e-12,
                                   "solver.atol_velocity": 1e-10})
    w = math.sqrt(K / M)
    t = r["time"]
    assert np.max(np.abs(r["tip.x"] - (L0 + (X0 - L0) * np.cos(w * t)))) < 1e-6
    # The velocity (amplitude 1 m/s) carries the same relative error (measured 9.3e-8 m/s).
    assert np.max(np.abs(r["tip.vx"] + (X0 - L0) * w * np.sin(w * t))) < 1e-6
    # Energy is conserved (no damping): kinetic + elastic stays at k (x0 - l0)^2 / 2 = 1 J, to
    # about twice the relative error of the state, which the tolerances keep below 5e-7 of the
    # amplitude over these 300 steps (measured 1.1e-7; the energy 2.4e-7 J).
    total = r["energy.kinetic"] + r["energy.elastic"]
    assert np.max(np.abs(total - 0.5 * K * (X0 - L0) ** 2)) < 1e-6
    # The motion port carries the spring force: the model pulls the anchor towards the bob. The
    # same state, so only round-off (measured 1.8e-15 N).
    assert np.max(np.abs(r["base.fx"] - K * (r["tip.x"] - L0))) < 1e-12


def test_frequency_scales_with_sqrt_k_over_m(test_fmu):
    # Four times the stiffness halves the period: x(t; 4k) = x(2t; k) exactly, and so does a
    # quarter of the mass. Both runs are compared at matching phases within the integrator's
    # tolerance (rtol 1e-10, amplitude 0.2 m: 1e-6 m is generous).
    fmu = str(test_fmu("driven_oscillator"))
    tight = {"solver.rtol": 1e-10, "solver.atol_position": 1e-12, "solver.atol_velocity": 1e-10}
    slow = simulate_fmu(fmu, stop_time=2.0, output_interval=0.02, start_values=tight)
    stiff = simulate_fmu(fmu, stop_time=1.0, output_interval=0.01, start_values=dict(tight, k=4 * K))
    light = simulate_fmu(fmu, stop_time=1.0, output_interval=0.01, start_values=dict(tight, m=M / 4))
    assert np.max(np.abs(stiff["tip.x"] - slow["tip.x"])) < 1e-6
    assert np.max(np.abs(light["tip.x"] - slow["tip.x"])) < 1e-6


def crossings(t, x, v):
    """Times at which x, sampled at t with its rate v, changes sign: the root of the cubic Hermite
    interpolant on each interval where it does, by bisection (the interpolant's error is
    O(h^4) of the motion: 1e-12 of a period at h = 1 ms)."""
    found = []
    for i in np.nonzero(np.signbit(x[:-1]) != np.signbit(x[1:]))[0]:
        h = t[i + 1] - t[i]

        def hermite(s):
            return ((2 * s**3 - 3 * s**2 + 1) * x[i] + (s**3 - 2 * s**2 + s) * h * v[i]
                    + (-2 * s**3 + 3 * s**2) * x[i + 1] + (s**3 - s**2) * h * v[i + 1])

        lo, hi = 0.0, 1.0
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if np.signbit(hermite(mid)) == np.signbit(hermite(lo)) else (lo, mid)
        found.append(t[i] + h * lo)
    return np.array(found)


@pytest.mark.parametrize("degrees", [10, 90, 150, 179])
def test_a_pendulum_swings_with_the_elliptic_integral_period(test_fmu, degrees):
    # The simple pendulum released from rest at theta0 from the downward vertical swings with the
    # period T = 4 sqrt(L / g) K(k), k = sin(theta0 / 2), K the complete elliptic integral of the
    # first kind (Landau and Lifshitz, Mechanics, section 11, problem 1): 1.0004 times the
    # small-angle 2 pi sqrt(L / g) at 10 degrees, 1.18 at 90, 1.76 at 150 and 3.9 at 179.
    # The rod is a spring of k = 1e7 N/m under a 1 kg bob, started at the length at which it
    # carries the bob's weight across it, m g cos(theta0) (so no axial oscillation starts); its
    # tension, m g (3 cos(theta) - 2 cos(theta0)), stretches it by at most 5 m g / k = 4.9e-6 m,
    # which lengthens the period by at most half that, relatively: 2.5e-6 (measured 5e-7 to
    # 2e-6). The bob crosses below the pivot every half period; rtol 1e-10 keeps the times
    # within 1e-8 of a period.
    g, length, k, m = 9.81, 1.0, 1e7, 1.0
    theta0 = math.radians(degrees)
    r0 = length + m * g * math.cos(theta0) / k
    r = simulate_fmu(str(test_fmu("pendulum")), stop_time=6.0, output_interval=0.001,
                     start_values={"x0": r0 * math.sin(theta0), "z0": -r0 * math.cos(theta0)})
    times = crossings(r["time"], r["bob.x"], r["bob.vx"])
    assert len(times) >= 2
    period = 2 * (times[-1] - times[0]) / (len(times) - 1)
    expected = 4 * math.sqrt(length / g) * scipy.special.ellipk(math.sin(theta0 / 2) ** 2)  # K(m = k^2)
    assert period == pytest.approx(expected, rel=5e-6)
    # The bob stays on its circle, to the spring's stretch, and the energy is conserved.
    assert np.max(np.abs(np.hypot(r["bob.x"], r["bob.z"]) - length)) < 5e-6
    energy = r["energy.kinetic"] + r["energy.elastic"] + r["energy.gravity"]
    assert np.max(np.abs(energy - energy[0])) < 1e-6


def test_a_parameter_set_after_an_output_was_read_in_initialisation_mode_counts(test_fmu):
    # FMI 2.0 lets a master read outputs in initialisation mode and then set parameters: the
    # values set count, the outputs read after them and the run that follows are the model's with
    # them. Four times the stiffness: the anchor's reaction k (x0 - l0) becomes 40 N at once,
    # and the bob oscillates as x(t) = l0 + (x0 - l0) cos(2 w t).
    inst = Instance(test_fmu("driven_oscillator"))
    s = inst.slave
    try:
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        for name, value in {"solver.rtol": 1e-10, "solver.atol_position": 1e-12,
                            "solver.atol_velocity": 1e-10}.items():
            inst.set(name, value)
        assert inst.get("base.fx") == pytest.approx(K * (X0 - L0), rel=1e-12)
        inst.set("k", 4 * K)
        assert inst.get("base.fx") == pytest.approx(4 * K * (X0 - L0), rel=1e-12)
        s.exitInitializationMode()
        w, h = math.sqrt(4 * K / M), 0.01
        for n in range(50):
            s.doStep(n * h, h)
            assert abs(inst.get("tip.x") - (L0 + (X0 - L0) * math.cos(w * (n + 1) * h))) < 1e-6
    finally:
        inst.free()


def test_force_port_driven_by_input_signal(test_fmu):
    # A constant force F on the bob from t = 0 moves the centre of oscillation to l0 + F/k:
    # x(t) = l0 + F/k + (x0 - l0 - F/k) cos(w t).
    F = 3.0
    fmu = str(test_fmu("driven_oscillator"))
    signal = np.array([(0.0, F), (2.0, F)], dtype=[("time", np.float64), ("tip.fx", np.float64)])
    r = simulate_fmu(fmu, stop_time=2.0, output_interval=0.01, input=signal,
                     start_values={"solver.rtol": 1e-10, "solver.atol_position": 1e-12,
                                   "solver.atol_velocity": 1e-10})
    w = math.sqrt(K / M)
    expected = L0 + F / K + (X0 - L0 - F / K) * np.cos(w * r["time"])
    assert np.max(np.abs(r["tip.x"] - expected)) < 1e-6


@pytest.mark.parametrize("stop_time", [None, 1.0], ids=["no stop time", "stop time"])
def test_force_step_changes_result_from_that_point(test_fmu, stop_time):
    # A force switched on at t1 leaves the motion before t1 untouched and shifts the centre of
    # oscillation afterwards (checked against the closed form of the piecewise problem). With a
    # stop time CVODE has stepped past t1 when the force comes, and restarts at t1.
    F, t1 = 2.0, 0.5
    inst = Instance(test_fmu("driven_oscillator")).start(
        {"solver.rtol": 1e-10, "solver.atol_position": 1e-12, "solver.atol_velocity": 1e-10}, stop_time=stop_time)
    w = math.sqrt(K / M)
    h, t = 0.01, 0.0
    try:
        for n in range(100):
            if abs(t - t1) < 1e-12:
                inst.set("tip.fx", F)
            inst.slave.doStep(t, h)
            t = (n + 1) * h
            x = inst.get("tip.x")
            if t <= t1 + 1e-12:
                expected = L0 + (X0 - L0) * math.cos(w * t)
            else:
                x1 = L0 + (X0 - L0) * math.cos(w * t1)
                v1 = -(X0 - L0) * w * math.sin(w * t1)
                c = L0 + F / K
                expected = c + (x1 - c) * math.cos(w * (t - t1)) + v1 / w * math.sin(w * (t - t1))
            assert abs(x - expected) < 1e-6, (t, x, expected)
    finally:
        inst.free()


def solver_steps(inst):
    """Internal steps of every communication step so far, from the logSolver messages."""
    return [r.steps for r in inst.solver_reports()]


def logged_driven_oscillator(test_fmu, stop_time):
    """The driven oscillator at tight tolerances, started with the stop time given (or none), its
    solver statistics logged."""
    inst = Instance(test_fmu("driven_oscillator"), logging_on=True)
    inst.slave.setDebugLogging(True, ["logSolver"])
    return inst.start({"solver.rtol": 1e-10, "solver.atol_position": 1e-12, "solver.atol_velocity": 1e-10},
                      stop_time=stop_time)


def stepped_driven_oscillator(test_fmu, stop_time, steps, h, before_step, outputs):
    """logged_driven_oscillator advanced `steps` communication steps of h seconds from 0, with
    before_step(inst, n) called before step n: the outputs named after every step (a row per step)
    and the internal steps of each (solver_steps)."""
    inst = logged_driven_oscillator(test_fmu, stop_time)
    try:
        x = []
        for n in range(steps):
            before_step(inst, n)
            inst.slave.doStep(n * h, h)
            x.append(inst.get(*outputs))
        return np.array(x), solver_steps(inst)
    finally:
        inst.free()


def held_or_changing_force(test_fmu, stop_time, changing):
    """The driven oscillator over 1 s in 1 ms communication steps; tip.fx held at 0 or changed
    at every step (1e-3 N, alternating in sign). Returns tip.x per step and the internal steps."""
    inst = logged_driven_oscillator(test_fmu, stop_time)
    try:
        x = []
        for n in range(1000):
            if changing:
                inst.set("tip.fx", 1e-3 * (-1) ** n)
            inst.slave.doStep(n * 1e-3, 1e-3)
            x.append(inst.get("tip.x"))
        return np.array(x), solver_steps(inst)
    finally:
        inst.free()


def test_with_a_stop_time_and_held_inputs_cvode_steps_past_communication_points(test_fmu):
    # With the stop time given and the inputs held, CVODE steps as its tolerances allow and the
    # outputs are interpolated: far fewer internal steps than communication steps, where without
    # a stop time every communication step ends one. Both follow the closed form (rtol 1e-10:
    # 1e-6 m, as above).
    w = math.sqrt(K / M)
    expected = L0 + (X0 - L0) * np.cos(w * 1e-3 * np.arange(1, 1001))
    x_stop, steps_stop = held_or_changing_force(test_fmu, 1.0, False)
    x_free, steps_free = held_or_changing_force(test_fmu, None, False)
    assert len(steps_stop) == len(steps_free) == 1000
    assert sum(steps_free) >= 1000 and min(steps_free) >= 1
    assert sum(steps_stop) < 0.5 * 1000 and steps_stop.count(0) > 500
    assert np.max(np.abs(x_stop - expected)) < 1e-6 and np.max(np.abs(x_free - expected)) < 1e-6
    # An input that changes at every communication point (a coupled master's) makes every step
    # end at the point, with or without a stop time: the same computation, bit for bit.
    x_stop, steps_stop = held_or_changing_force(test_fmu, 1.0, True)
    x_free, steps_free = held_or_changing_force(test_fmu, None, True)
    assert steps_stop == steps_free and min(steps_stop) >= 1
    assert np.array_equal(x_stop, x_free)


def test_held_inputs_from_an_fmpy_input_table_restart_cvode_once(test_fmu):
    # fmpy sets the inputs at every point, interpolating its table between two rows as
    # w0 v0 + w1 v1: a held 1.3 N and the anchor's 1.3 m/s (from -1 m) come out an ulp off at
    # some points. Round-off is no change: CVODE restarts once, for the inputs leaving their start
    # values, and with the stop time given steps past the points (fewer internal steps than a
    # fifth of the 2000 points; measured 272). Each ulp restarted it: 199 restarts, 1610 steps.
    table = np.array([(0.0, 1.3, -1.0, 1.3), (2.0, 1.3, 1.6, 1.3)],
                     dtype=[("time", float), ("tip.fx", float), ("base.x", float), ("base.vx", float)])
    messages = []
    result = simulate_fmu(str(test_fmu("driven_oscillator")), stop_time=2.0, output_interval=1e-3,
                          input=table, debug_logging=True,
                          logger=lambda *args: messages.append(args[-1].decode()))
    solver = [re.search(r"(\d+) internal steps.* (\d+) restarts", m) for m in messages]
    solver = [(int(m.group(1)), int(m.group(2))) for m in solver if m]
    assert len(solver) == 2000
    assert sum(r for _, r in solver) == 1
    assert sum(s for s, _ in solver) < 400
    # The run of a master that sets the inputs once, to round-off (measured 1.8e-15 m).
    inst = Instance(test_fmu("driven_oscillator"))
    try:
        inst.start(stop_time=2.0)
        for name, value in (("tip.fx", 1.3), ("base.x", -1.0), ("base.vx", 1.3)):
            inst.set(name, value)
        x = []
        for n in range(2000):
            inst.slave.doStep(n * 1e-3, 1e-3)
            x.append(inst.get("tip.x"))
    finally:
        inst.free()
    assert np.max(np.abs(result["tip.x"][1:] - np.array(x))) < 1e-12


def test_a_master_that_sets_every_input_keeps_a_change_among_unchanged_ones(test_fmu):
    # A master that sets every input at every point: the anchor (base, applied before tip) moved
    # by 1e-6 m, alternating in sign, and tip.fx set again to 0 N, unchanged. The changed input
    # ends the step at the point whatever unchanged one is applied after it, so with the stop
    # time or without, the same computation, bit for bit (as for the changing force above).
    def set_every_input(inst, n):
        inst.set("base.x", 1e-6 * (-1) ** n)
        inst.set("tip.fx", 0.0)

    (x_stop, steps_stop), (x_free, steps_free) = (
        stepped_driven_oscillator(test_fmu, stop_time, 1000, 1e-3, set_every_input, ["tip.x"])
        for stop_time in (1.0, None))
    assert steps_stop == steps_free and min(steps_stop) >= 1
    assert np.array_equal(x_stop, x_free)


@pytest.mark.parametrize("name, value", [("tip.fx", 0.1), ("base.x", 0.01)])
def test_an_input_tried_and_set_back_before_a_step_changes_nothing(test_fmu, name, value):
    # A master that, before each step from 0.2 s on, sets an input to a trial value, reads an
    # output that depends on it, and sets it back (probing, or iterating at a communication point)
    # runs as one that never tried: the same internal steps and outputs, bit for bit. The input is
    # set to `value` from 0.1 s on, so that the runs share a change first. (A motion port's velocity
    # set alone is a change at every step whatever the master tries: its particle starts again
    # from the position held.)
    def set_input(trying):
        def before_step(inst, n):
            v = value if n >= 10 else 0.0
            if trying and n >= 20:
                inst.set(name, v + 0.5)
                x_trial = inst.get("base.fx")
                assert math.isfinite(x_trial)
            inst.set(name, v)
        return before_step

    (x_plain, steps_plain), (x_tried, steps_tried) = (
        stepped_driven_oscillator(test_fmu, 1.0, 100, 0.01, set_input(trying),
                                  ["tip.x", "tip.vx", "base.fx", "energy.input"])
        for trying in (False, True))
    assert steps_tried == steps_plain
    assert np.array_equal(x_tried, x_plain)


def test_a_parameter_set_away_and_back_in_one_call_changes_nothing(test_fmu):
    # One fmi2SetReal that gives the tunable k another value and then its own again (the same value
    # reference twice: the last value counts) leaves k as it was: the run goes on as one that made
    # no such call, with the same internal steps and outputs, bit for bit (no new model for the
    # simulation, whose CVODE would start afresh).
    def set_k_away_and_back(calling):
        def before_step(inst, n):
            if calling and n >= 20:
                inst.slave.setReal([inst.vr["k"], inst.vr["k"]], [60.0, 50.0])
                assert inst.get("k") == 50.0
        return before_step

    (x_plain, steps_plain), (x_called, steps_called) = (
        stepped_driven_oscillator(test_fmu, 1.0, 40, 0.01, set_k_away_and_back(calling),
                                  ["tip.x", "tip.vx", "base.fx", "energy.input"])
        for calling in (False, True))
    assert steps_called == steps_plain
    assert np.array_equal(x_called, x_plain)


def test_tolerances_coarse_for_the_model_are_a_warning_at_initialisation(tmp_path, package):
    # The bundled oscillator scaled to micrometres, picograms and milliseconds: its motion (0.1 um,
    # up to 0.6 mm/s) lies below the default absolute tolerances (1e-8 m, 1e-6 m/s), which hold it
    # to nothing (tests/python/test_cli.py measures the error). fmi2ExitInitializationMode says so
    # (fmi2Warning, logged under logStatusWarning), unless the absolute tolerances were set to suit
    # the model (1e-8 of its 0.5 um spring, 1e-6 of it per millisecond) during initialisation.
    length, time, mass = 1e-6, 1e-3, 1e-12
    model = tmp_path / "micro.json"
    model.write_text(json.dumps({
        "springmass": 1, "name": "micro", "gravity": [0, 0, 0],
        "particles": [{"name": "anchor", "position": [0, 0, 0], "fixed": True},
                      {"name": "bob", "position": [0.6 * length, 0, 0], "mass": mass}],
        "springs": [{"a": "anchor", "b": "bob", "stiffness": 40.0 * mass / time**2,
                     "damping": 0.4 * mass / time, "rest_length": 0.5 * length}],
        "ports": [{"name": "tip", "particle": "bob", "kind": "probe"}]}))
    suited = {"solver.atol_position": 1e-8 * length, "solver.atol_velocity": 1e-6 * length / time}
    for tolerances, warned in (({}, True), (suited, False)):
        inst = Instance(package(model), logging_on=True)
        try:
            s = inst.slave
            s.setupExperiment(startTime=0.0)
            s.enterInitializationMode()
            for name, value in tolerances.items():
                inst.set(name, value)
            assert s.exitInitializationMode() == (1 if warned else 0)  # fmi2Warning, fmi2OK
            coarse = [m for m in inst.messages if "are coarse for this model" in m[2]]
            assert [m[1] for m in coarse] == (["logStatusWarning"] if warned else [])
            if warned:
                # The tolerances in use, the scales (the 0.5 length spring, moving at up to that
                # times the bob's sqrt(k / m)) and 1e-8 of these, the tolerances that suit them.
                speed = 0.5 * length * math.sqrt(40.0 / time**2)
                text = coarse[0][2]
                assert "solver.atol_position = 1e-08 m and solver.atol_velocity = 1e-06 m/s" in text, text
                assert f"shortest spring is {0.5 * length:.3g} m and moves at up to {speed:.3g} m/s" in text, text
                assert f"scales, {5e-9 * length:.1g} m and {1e-8 * speed:.1g} m/s, set during" in text, text
            s.doStep(0.0, time)  # and it simulates as asked
        finally:
            inst.free()


def test_velocity_tolerances_too_tight_for_a_stiff_spring_are_a_warning_at_initialisation(tmp_path, package):
    # A 1 kg bob at rest 1 m below a pivot on a critically damped 1e9 N/m rod: rounding its force
    # moves the bob's velocity by up to eps sqrt(1e9) / 2 = 3.5e-12 m/s in a step
    # (sm_model_round_off); a velocity tolerance below a tenth of that makes CVODE's steps fail
    # over and over. `springmass fmu` warns at packaging, fmi2ExitInitializationMode with
    # fmi2Warning, unless a tolerance above it is set during initialisation.
    model = tmp_path / "rod.json"
    model.write_text(json.dumps({
        "springmass": 1, "name": "rod", "gravity": [0, 0, -9.81],
        "particles": [{"name": "pivot", "position": [0, 0, 0], "fixed": True},
                      {"name": "bob", "position": [0, 0, -1], "mass": 1}],
        "springs": [{"a": "pivot", "b": "bob", "stiffness": 1e9, "damping": 2 * math.sqrt(1e9), "rest_length": 1}],
        "ports": [{"name": "tip", "particle": "bob", "kind": "probe"}],
        "simulation": {"atol_velocity": 1e-14}}))
    packed = subprocess.run([CLI, "fmu", model, "-o", tmp_path / "rod.fmu"], capture_output=True, text=True)
    assert packed.returncode == 0, packed.stderr
    assert "springmass fmu: warning: the absolute tolerance of velocities, 1e-14 m/s, is too tight" in packed.stderr
    noise = 2.220446049250313e-16 * math.sqrt(1e9) / 2
    for tolerances, warned in (({}, True), ({"solver.atol_velocity": 1e-10}, False)):
        inst = Instance(package(model), logging_on=True)
        try:
            s = inst.slave
            s.setupExperiment(startTime=0.0)
            s.enterInitializationMode()
            for name, value in tolerances.items():
                inst.set(name, value)
            assert s.exitInitializationMode() == (1 if warned else 0)  # fmi2Warning, fmi2OK
            tight = [m for m in inst.messages if "is too tight for the round-off" in m[2]]
            assert [m[:2] for m in tight] == ([(1, "logStatusWarning")] if warned else [])  # fmi2Warning
            if warned:
                text = tight[0][2]
                assert "solver.atol_velocity = 1e-14 m/s" in text and "spring 0, 1e+09 N/m" in text, text
                assert f"by up to {noise:.2g} m/s" in text and f"{0.1 * noise:.2g} m/s or more" in text, text
        finally:
            inst.free()


def stepped_from(test_fmu, start_time):
    """The driven oscillator from start_time over 1 s in communication steps of 1/128 s, with the
    stop time start_time + 1 s given. Returns tip.x and tip.vx per step and the internal steps."""
    inst = Instance(test_fmu("driven_oscillator"), logging_on=True)
    inst.slave.setDebugLogging(True, ["logSolver"])
    inst.start(start_time=start_time, stop_time=start_time + 1.0)
    try:
        h, states = 1.0 / 128, []
        for n in range(128):
            inst.slave.doStep(start_time + n * h, h)
            states.append(inst.get("tip.x", "tip.vx"))
        assert inst.slave.getRealStatus(2) == start_time + 1.0  # fmi2LastSuccessfulTime
        return np.array(states), solver_steps(inst)
    finally:
        inst.free()


def test_stability_limit_detection_is_a_parameter_and_either_way_the_rope_settles(package, tmp_path):
    # The bundled hanging rope with 10 segments and mass damping 1 1/s: every mode decays at least
    # like exp(-t / 2), so after 100 s it hangs at its static equilibrium to round-off. One
    # communication step of 100 s: with BDF's stability limit detection (the default) CVODE took
    # 13 090 internal steps, without it 24 868 (its lightly damped lengthwise vibrations keep the
    # steps short; measured, as `springmass run` takes them). Asserted: the parameter reaches
    # CVODE (at least 1.5 times the steps without it), and either way the probes hang within
    # 1e-10 m of `springmass statics`'s rest shape (measured 1.8e-13 m and 3e-14 m), a hundredth
    # of the position tolerance atol 1e-8 m.
    rope = ROOT / "models" / "hanging_rope.json"
    sets = ("alpha=1", "n=10")
    subprocess.run([str(CLI), "statics", str(rope), "-q", "-o", str(tmp_path / "rest.csv"),
                    *[w for s in sets for w in ("--set", s)]], check=True, capture_output=True)
    rest = np.loadtxt(tmp_path / "rest.csv", delimiter=",", skiprows=1, usecols=(2, 3, 4))
    steps = {}
    for detection in (True, False):
        inst = Instance(package(rope, sets), logging_on=True)
        try:
            vr = [inst.vr["solver.stability_limit_detection"]]
            s = inst.slave
            s.setupExperiment(startTime=0.0)
            s.enterInitializationMode()
            assert s.getBoolean(vr) == [True]
            with pytest.raises(FMICallException):
                s.setBoolean(vr, [2])
            assert "must be fmi2True (1) or fmi2False (0)" in inst.log_text()
            # A refused call changes nothing, a good value before the bad one included.
            with pytest.raises(FMICallException):
                s.setBoolean(vr * 2, [False, 2])
            assert s.getBoolean(vr) == [True]
            s.setBoolean(vr, [detection])
            s.exitInitializationMode()
            assert s.getBoolean(vr) == [detection]
            s.setDebugLogging(True, ["logSolver"])
            s.doStep(0.0, 100.0)
            steps[detection] = sum(r.steps for r in inst.solver_reports())
            for probe, particle in (("tip", 10), ("middle", 5)):
                position = inst.get(f"{probe}.x", f"{probe}.y", f"{probe}.z")
                assert np.max(np.abs(np.array(position) - rest[particle])) <= 1e-10, (detection, probe)
        finally:
            inst.free()
    assert steps[False] >= 1.5 * steps[True], steps


def test_stability_limit_detection_set_after_an_output_was_read_takes_effect(package):
    # In initialisation mode an output read builds the simulation; solver.stability_limit_detection
    # switched off after that must reach CVODE as it does when set before any read. The hanging rope
    # of 10 segments with mass damping 1 1/s over one step of 2 s: 2234 internal steps with the
    # detection, 2300 without (measured, as `springmass run` takes them), so the runs with it off,
    # the output read first or not, are the same run to the bit, and not the run with it on.
    rope = package(ROOT / "models" / "hanging_rope.json", ("alpha=1", "n=10"))
    runs = {}
    for case in ("on", "off", "off after a read"):
        inst = Instance(rope, logging_on=True)
        try:
            s = inst.slave
            s.setupExperiment(startTime=0.0)
            s.enterInitializationMode()
            if case == "off after a read":
                inst.get("tip.x")
            if case != "on":
                s.setBoolean([inst.vr["solver.stability_limit_detection"]], [False])
            s.exitInitializationMode()
            s.setDebugLogging(True, ["logSolver"])
            s.doStep(0.0, 2.0)
            steps = sum(r.steps for r in inst.solver_reports())
            runs[case] = (steps, inst.get("tip.x", "tip.z", "middle.x", "middle.z"))
        finally:
            inst.free()
    assert runs["off after a read"] == runs["off"], runs
    assert runs["off"][0] != runs["on"][0], runs


def test_with_a_stop_time_the_run_does_not_depend_on_the_start_time(test_fmu):
    # The model knows no absolute time: started at 4 s with the stop time 5 s, the run is the one
    # started at 0 s with the stop time 1 s, bit for bit (the same internal steps, the same
    # outputs), the stop time counted from the start as the communication points are. Steps of
    # 1/128 s from 0 or 4 s are sums exact in binary, so that both runs see the same times.
    states_0, steps_0 = stepped_from(test_fmu, 0.0)
    states_4, steps_4 = stepped_from(test_fmu, 4.0)
    assert sum(steps_0) < 128  # CVODE steps past communication points
    assert steps_4 == steps_0
    assert np.array_equal(states_4, states_0)


def test_a_last_step_within_round_off_past_the_stop_time_is_taken(test_fmu):
    # Three steps of 0.1 s to the stop time 0.3 s end at 0.2 + 0.1 = 0.30000000000000004 s, one
    # ulp past it, which fmi2DoStep allows (up to 1000 ulps): CVODE then stops at that end, not
    # at the stop time before it, and the bob is where the closed form puts it (rtol 1e-10:
    # 1e-6 m, as above).
    inst = Instance(test_fmu("driven_oscillator")).start(
        {"solver.rtol": 1e-10, "solver.atol_position": 1e-12, "solver.atol_velocity": 1e-10}, stop_time=0.3)
    try:
        for n in range(3):
            inst.slave.doStep(0.1 * n, 0.1)
        t = 0.1 * 2 + 0.1
        assert t > 0.3 and inst.slave.getRealStatus(2) == t  # fmi2LastSuccessfulTime
        w = math.sqrt(K / M)
        assert abs(inst.get("tip.x") - (L0 + (X0 - L0) * math.cos(w * t))) < 1e-6
    finally:
        inst.free()


def test_motion_port_reaction_matches_statics(test_fmu):
    # hanging.json: a bob of m = 0.5 kg on a damped spring (k = 200 N/m, d = 20 N s/m, l0 = 0.3 m)
    # under a hook of 0.1 kg that is a motion port, in a medium with mass damping alpha = 10 1/s.
    # The hook moves at a constant velocity v along a slanted line. Once the transients have
    # decayed (the slowest, the pendulum swing, as e^(-alpha t / 2): e^-15 after 3 s) the bob
    # moves with the same velocity and nothing accelerates, so statics holds:
    #   spring force on the bob  f_s = -m g + alpha m v   (balances weight and drag)
    #   force on the hook        F = (m + m_hook) g - alpha (m + m_hook) v
    #   bob - hook               = -(l0 + |f_s| / k) f_s / |f_s|
    m, m_hook, k, l0, alpha = 0.5, 0.1, 200.0, 0.3, 10.0
    g = np.array([0.0, 0.0, -9.81])
    velocity = np.array([0.05, -0.02, 0.1])
    inst = Instance(test_fmu("hanging")).start()
    h, t = 0.01, 0.0
    try:
        for n in range(300):
            position = velocity * t
            for c, axis in enumerate("xyz"):
                inst.set(f"hook.{axis}", position[c])
                inst.set(f"hook.v{axis}", velocity[c])
            inst.slave.doStep(t, h)
            t = (n + 1) * h
        force = np.array(inst.get("hook.fx", "hook.fy", "hook.fz"))
        hook = np.array(inst.get("hook.x", "hook.y", "hook.z"))
        bob = np.array(inst.get("bob.x", "bob.y", "bob.z"))
        bob_velocity = np.array(inst.get("bob.vx", "bob.vy", "bob.vz"))
        f_s = -m * g + alpha * m * velocity
        stretch = l0 + np.linalg.norm(f_s) / k
        # Tolerances: what is left of the transients is below 1e-6 of the initial ones; the rest
        # is the integrator's error, default rtol 1e-6 on forces of about 6 N (6e-6 N; measured
        # 5.7e-9 N), on positions of 0.3 m and velocities of 0.1 m/s (measured 3.4e-10 m and
        # 1.3e-8 m/s).
        assert np.allclose(force, (m + m_hook) * g - alpha * (m + m_hook) * velocity, atol=1e-5)
        # The input reads what was set last (at t - h); the hook itself is at v t.
        assert np.allclose(hook, velocity * (t - h), atol=1e-12)
        assert np.allclose(bob - velocity * t, -stretch * f_s / np.linalg.norm(f_s), atol=1e-6)
        assert np.allclose(bob_velocity, velocity, atol=1e-6)
    finally:
        inst.free()


def test_directional_derivative_is_the_stiffness_seen_by_the_port(test_fmu):
    # d(base.fx)/d(base.x) from the analytic Jacobian equals a central finite difference of the
    # output, and for a spring along x it is -k: moving the anchor towards the bob shortens the
    # spring and reduces the pull on the anchor. Finite differences with h = 1e-6 m are exact to
    # about 1e-8 relative for this quadratic-free (linear in x) force.
    inst = Instance(test_fmu("driven_oscillator")).start()
    try:
        vr = inst.vr
        known = [vr["base.x"], vr["base.y"], vr["base.vx"]]
        # p[0] is the anchor, the motion port's particle: it is where base puts it.
        unknown = [vr["base.fx"], vr["base.fy"], vr["energy.elastic"], vr["tip.x"], vr["p[0].x"], vr["p[0].vx"]]
        d = inst.slave.getDirectionalDerivative(unknown, [vr["base.x"]], [1.0])
        assert abs(d[0] - (-K)) < 1e-9 * K
        assert abs(d[1]) < 1e-12
        # Elastic energy k (L - l0)^2 / 2 with L = x_bob - x_anchor: dE/dx_anchor = -k (L - l0).
        assert abs(d[2] - (-K * (X0 - L0))) < 1e-9
        assert d[3] == 0.0  # the bob's position is a state: no direct feed-through
        assert d[4] == 1.0 and d[5] == 0.0
        # Against finite differences of the outputs (and of the anchor's position and velocity),
        # for every known.
        for kv in known:
            name = inst.md.modelVariables[kv].name
            fd = central_difference(inst.slave, unknown, [kv], np.array(inst.slave.getReal([kv])), np.ones(1))
            analytic = np.array(inst.slave.getDirectionalDerivative(unknown, [kv], [1.0]))
            assert np.allclose(analytic, fd, rtol=1e-6, atol=1e-6), (name, analytic, fd)
    finally:
        inst.free()


def test_directional_derivatives_of_a_moving_damped_system_match_finite_differences(test_fmu):
    # hanging: a bob on a damped spring under gravity, in a viscous medium, its hook swung about
    # so that positions and velocities are all non-zero. One call with every motion input seeded
    # at once (seeds of different sizes and signs) against a central finite difference of the
    # outputs along the same direction: the reaction (stiffness and damping), the three energies,
    # the inputs' work (a motion set elsewhere does the work of the energy it adds at once: the
    # three energies' sum) and the hook's own position and velocity. h = 1e-6: round-off of outputs of order 10 over
    # 2h gives about 1e-9, the h^2 truncation about 1e-11: rtol and atol 1e-6.
    inst = Instance(test_fmu("hanging")).start()
    try:
        s, vr = inst.slave, inst.vr
        known = [vr[n] for n in ("hook.x", "hook.y", "hook.z", "hook.vx", "hook.vy", "hook.vz")]
        for n in range(5):
            s.setReal(known, [0.02 * n, -0.01 * n, 0.03 * n, 0.2, -0.1, 0.3])
            s.doStep(0.01 * n, 0.01)
        names = ["hook.fx", "hook.fy", "hook.fz", "energy.kinetic", "energy.elastic", "energy.gravity",
                 "energy.input", "p[0].x", "p[0].vz", "bob.x"]
        unknown = [vr[n] for n in names]
        # The inputs set for the next step: the hook moves from them (a motion input is where the
        # port is at the start of the step it is set for), so the derivatives and the finite
        # differences are taken at the same point.
        x = np.array([0.1, -0.05, 0.15, 0.2, -0.1, 0.3])
        s.setReal(known, list(x))
        seed = np.array([2.5, -1.0, 0.7, 1.5, -0.3, 0.9])
        analytic = np.array(s.getDirectionalDerivative(unknown, known, list(seed)))
        fd = central_difference(s, unknown, known, x, seed)
        assert np.allclose(analytic, fd, rtol=1e-6, atol=1e-6), list(zip(names, analytic, fd))
        # Not all zero: every output but the bob's position (a state) depends on the seeds.
        assert np.all(np.abs(analytic[:-1]) > 1e-3) and analytic[-1] == 0.0, list(zip(names, analytic))
        # The ModelStructure lists exactly the inputs an output's derivative depends on (a moving,
        # damped state, where none vanishes by accident): the reaction and the inputs' work all
        # six, the kinetic energy the velocities, the elastic energy the positions and, gravity
        # being along z, the gravitational energy hook.z alone.
        for output in inst.md.outputs:
            listed = {d.name for d in output.dependencies}
            for k in known:
                name = inst.md.modelVariables[k].name
                d = s.getDirectionalDerivative([output.variable.valueReference], [k], [1.0])[0]
                assert (d != 0.0) == (name in listed), (output.variable.name, name, d, sorted(listed))
    finally:
        inst.free()


@pytest.mark.parametrize("accelerating", [False, True])
def test_output_derivatives_are_the_rates_of_the_outputs(test_fmu, accelerating):
    # hanging: a bob on a damped spring under gravity, in a viscous medium, its hook moving at a
    # held velocity, or accelerating with the derivatives of its velocity inputs (the hook's force
    # then changes with the spring's damping times the hook's acceleration). The first derivative of every output at a communication point against a
    # three-point forward difference of the outputs over two more steps of h from a saved state,
    # with the hook moving on as it did: truncation h^2/3 times the third derivative (up to about
    # 1e3: the bob swings at 20 rad/s) gives 3e-8 at h = 1e-5, round-off of outputs of order 1
    # over h about 1e-11, the integration at rtol 1e-12 less: rtol and atol 1e-6.
    inst = Instance(test_fmu("hanging")).start({"solver.rtol": 1e-12, "solver.atol_position": 1e-14,
                                               "solver.atol_velocity": 1e-14})
    try:
        s, vr = inst.slave, inst.vr
        known = [vr[n] for n in ("hook.x", "hook.y", "hook.z", "hook.vx", "hook.vy", "hook.vz")]
        s.setReal(known, [0.0, 0.0, 0.0, 0.2, -0.1, 0.3])
        if accelerating:
            s.setRealInputDerivatives(known[3:], [1, 1, 1], [1.5, -2.0, 0.7])
        t = 0.0
        for _ in range(5):
            s.doStep(t, 0.01)
            t += 0.01
        outputs = [v.name for v in inst.md.modelVariables if v.causality == "output"]
        assert len(outputs) == 14  # the hook's force, the bob's position and velocity, five energies
        refs = [vr[n] for n in outputs]
        rates = np.array(s.getRealOutputDerivatives(refs, [1] * len(refs)))
        # A position's rate is the velocity output itself, bit for bit.
        for c in "xyz":
            assert rates[outputs.index(f"bob.{c}")] == inst.get(f"bob.v{c}")
        h = 1e-5
        saved = s.getFMUstate()
        y = [np.array(s.getReal(refs))]
        for k in range(2):
            s.doStep(t + k * h, h)
            y.append(np.array(s.getReal(refs)))
        s.setFMUstate(saved)
        s.freeFMUstate(saved)
        fd = (-3 * y[0] + 4 * y[1] - y[2]) / (2 * h)
        assert np.allclose(rates, fd, rtol=1e-6, atol=1e-6), list(zip(outputs, rates, fd))
        # None vanishes by accident at this moving, damped state.
        assert np.all(np.abs(rates) > 1e-3), list(zip(outputs, rates))
        # The same after the state was set back: the rates are those of the state and inputs.
        assert s.getRealOutputDerivatives(refs, [1] * len(refs)) == list(rates)
        # Other orders, other causalities: fmi2Error with a message, nothing else changed.
        before = len(inst.messages)
        for ref, order in ((vr["bob.x"], 2), (vr["bob.x"], 0), (vr["hook.x"], 1), (vr["k"], 1)):
            with pytest.raises(FMICallException):
                s.getRealOutputDerivatives([ref], [order])
        texts = [m[2] for m in inst.messages[before:]]
        assert "order 2 of bob.x: this FMU gives first derivatives (maxOutputDerivativeOrder = 1)" in texts[0]
        assert "order 0 of bob.x" in texts[1] and "hook.x is not an output" in texts[2] and "k is not" in texts[3]
        assert s.getRealOutputDerivatives(refs, [1] * len(refs)) == list(rates)
        # A motion input far beyond the model's scale: derivatives beyond a double come with
        # fmi2Warning and the first such output named, as fmi2GetReal gives the values.
        s.setReal([vr["hook.x"]], [1e160])
        values = (ctypes.c_double * len(refs))()
        status = s.fmi2GetRealOutputDerivatives(s.component, (ctypes.c_uint * len(refs))(*refs), len(refs),
                                                (ctypes.c_int * len(refs))(*[1] * len(refs)), values)
        assert status == 1 and not all(math.isfinite(v) for v in values)
        assert "the derivative of hook.fx is not finite" in inst.messages[-1][2], inst.messages[-1]
    finally:
        inst.free()


def test_output_derivatives_of_the_oscillator_follow_its_equation(test_fmu):
    # driven_oscillator: a bob of mass M on a spring K of rest length L0 from an anchor held at
    # the origin: its acceleration is -K (x - L0) / M along x, the force on the anchor K (x - L0)
    # changes at K vx (the force port's input is 0).
    inst = Instance(test_fmu("driven_oscillator")).start()
    try:
        s, vr = inst.slave, inst.vr
        s.doStep(0.0, 0.05)
        x, vx = inst.get("tip.x", "tip.vx")
        names = ["tip.x", "tip.vx", "base.fx"]
        rates = s.getRealOutputDerivatives([vr[n] for n in names], [1, 1, 1])
        assert rates[0] == vx
        assert rates[1] == pytest.approx(-K * (x - L0) / M, rel=1e-12)
        assert rates[2] == pytest.approx(K * vx, rel=1e-12)
        assert inst.md.coSimulation.maxOutputDerivativeOrder == 1
    finally:
        inst.free()


def test_output_derivatives_keep_a_held_particle_still(package, tmp_path):
    # From mutation testing: a held particle does not accelerate, whatever the springs pull it with.
    # A wall held at the origin (probe w, 2 kg) and the motion port hook, joined by a spring of
    # 100 N/m and 5 N s/m, rest length 0.4 m, the hook moving away along x at 0.2 m/s from 0.5 m.
    # The rates of w's velocity are 0, and the hook's force -k (L - l0) - d (vx_hook - vx_wall) along
    # x changes at -k vx_hook = -20 N/s, neither end accelerating (the spring stays along x). Taking
    # f / m as the held wall's acceleration too (13 N / 2 kg at 0.1 s) gave w.vx the rate
    # 6.5 m/s^2 and the hook's force 12.5 N/s, and no test failed.
    model = tmp_path / "held_wall.json"
    model.write_text(json.dumps({
        "springmass": 1, "name": "held_wall", "gravity": [0, 0, -9.81],
        "particles": [{"name": "wall", "position": [0, 0, 0], "mass": 2.0, "fixed": True},
                      {"name": "hook", "position": [0.5, 0, 0], "mass": 1.0, "fixed": True}],
        "springs": [{"a": "wall", "b": "hook", "stiffness": 100.0, "damping": 5.0, "rest_length": 0.4}],
        "ports": [{"name": "w", "particle": "wall", "kind": "probe"},
                  {"name": "hook", "particle": "hook", "kind": "motion"}]}))
    inst = Instance(package(model)).start({"hook.vx": 0.2})
    try:
        s, vr = inst.slave, inst.vr
        s.doStep(0.0, 0.1)
        assert inst.get("w.x") == 0.0
        names = ["w.x", "w.y", "w.z", "w.vx", "w.vy", "w.vz", "hook.fx", "hook.fy", "hook.fz"]
        rates = s.getRealOutputDerivatives([vr[n] for n in names], [1] * len(names))
        assert rates[:6] == [0.0] * 6, list(zip(names, rates))
        # Rounding only: the Jacobian's product adds terms of order k L and d.
        assert rates[6] == pytest.approx(-100.0 * 0.2, rel=1e-12, abs=1e-12)
        assert rates[7:] == pytest.approx([0.0, 0.0], abs=1e-12)
    finally:
        inst.free()


TIGHT = {"solver.rtol": 1e-10, "solver.atol_position": 1e-12, "solver.atol_velocity": 1e-10}


def test_a_force_input_ramps_with_its_derivative(test_fmu):
    # canInterpolateInputs: d(tip.fx)/dt = r set once at t = 0 pushes the bob with r t over every
    # step that follows: M u'' + K u = r t from u(0) = x0 - l0, u'(0) = 0 gives
    # u = (x0 - l0) cos(w t) + r / K (t - sin(w t) / w). At rtol 1e-10 the global error over 2 s
    # stays far below 1e-6 m, as in test_oscillator_matches_closed_form. A master that sets the
    # value r t and the derivative again at every point continues the same ramp (the same steps:
    # the positions agree to round-off, 1e-12 m); the input reads the value as set.
    r, w, h = 3.0, math.sqrt(K / M), 0.1
    runs = []
    for every_point in (False, True):
        inst = Instance(test_fmu("driven_oscillator")).start(TIGHT)
        try:
            s, vr = inst.slave, inst.vr
            s.setRealInputDerivatives([vr["tip.fx"]], [1], [r])
            xs = []
            for n in range(20):
                if every_point and n > 0:
                    inst.set("tip.fx", r * n * h)
                    s.setRealInputDerivatives([vr["tip.fx"]], [1], [r])
                s.doStep(n * h, h)
                xs.append(inst.get("tip.x"))
            assert inst.get("tip.fx") == (r * 19 * h if every_point else 0.0)
            runs.append(np.array(xs))
        finally:
            inst.free()
    t = h * np.arange(1, 21)
    u = (X0 - L0) * np.cos(w * t) + r / K * (t - np.sin(w * t) / w)
    assert np.max(np.abs(runs[0] - (L0 + u))) < 1e-6
    assert np.max(np.abs(runs[1] - runs[0])) < 1e-12


def test_a_motion_port_accelerates_with_its_velocity_derivative(test_fmu):
    # d(base.vx)/dt = a set once at t = 0: the anchor moves along a t^2 / 2 from rest, and in its
    # (accelerating) frame the bob obeys M u'' = -K u - M a, u = x_bob - x_anchor - l0, from
    # u(0) = x0 - l0 at rest: u = -M a / K + (x0 - l0 + M a / K) cos(w t). The force on the anchor
    # is K u. Errors as in the ramp test (1e-6 m; K times that for the force). The derivative of
    # base.x is the velocity input's business: taken, not used. The reaction's output derivative
    # at the end is K u' (relative error as the state's).
    a, w, h = 0.8, math.sqrt(K / M), 0.1
    inst = Instance(test_fmu("driven_oscillator")).start(TIGHT)
    try:
        s, vr = inst.slave, inst.vr
        s.setRealInputDerivatives([vr["base.vx"], vr["base.x"]], [1, 1], [a, 123.0])
        worst_x = worst_f = 0.0
        for n in range(20):
            s.doStep(n * h, h)
            t = (n + 1) * h
            u = -M * a / K + (X0 - L0 + M * a / K) * math.cos(w * t)
            x, f = inst.get("tip.x", "base.fx")
            worst_x = max(worst_x, abs(x - (0.5 * a * t * t + L0 + u)))
            worst_f = max(worst_f, abs(f - K * u))
        assert worst_x < 1e-6 and worst_f < K * 1e-6, (worst_x, worst_f)
        du = -(X0 - L0 + M * a / K) * w * math.sin(w * 2.0)
        (rate,) = s.getRealOutputDerivatives([vr["base.fx"]], [1])
        assert rate == pytest.approx(K * du, rel=1e-6)
    finally:
        inst.free()


# The driven oscillator of the harmonic inputs below: damping ratio ZETA = d / (2 sqrt(K M)) = 0.2
# (d = DAMPING = 4 N s/m), natural frequency W0 = sqrt(K / M) = 5 rad/s, so that a transient
# decays as exp(-ZETA W0 t) = exp(-t / 1 s).
ZETA = 0.2
W0 = math.sqrt(K / M)
DAMPING = 2 * ZETA * math.sqrt(K * M)


def steady_harmonic_response(fmu, set_inputs, w, steps_per_period):
    """Runs the driven oscillator at TIGHT tolerances and damping DAMPING, setting its inputs with
    set_inputs(instance, t, h) before every step of h = 2 pi / w / steps_per_period, for 16 s (16
    decay times: the start's transient, about 0.2 m, falls below 3e-8 m) and two periods more.
    Returns the bob's positions at the points of the last two periods fitted by least squares as
    c + amplitude sin(w t + phase), (amplitude [m], phase [rad]), the energy dissipated and the
    inputs' work over the last period [J], and h [s]."""
    h = 2 * math.pi / w / steps_per_period
    periods = math.ceil(16.0 * w / (2 * math.pi)) + 2
    inst = Instance(fmu).start({**TIGHT, "d": DAMPING})
    times, positions, energies = [], [], []
    try:
        for n in range(periods * steps_per_period):
            t = n * h
            set_inputs(inst, t, h)
            if n % steps_per_period == 0 and n >= (periods - 1) * steps_per_period:
                energies.append(inst.get("energy.dissipated", "energy.input"))
            inst.slave.doStep(t, h)
            if n >= (periods - 2) * steps_per_period:
                times.append(t + h)
                positions.append(inst.get("tip.x"))
        energies.append(inst.get("energy.dissipated", "energy.input"))
    finally:
        inst.free()
    t = np.array(times)
    basis = np.column_stack([np.sin(w * t), np.cos(w * t), np.ones_like(t)])
    (a, b, _), *_ = np.linalg.lstsq(basis, np.array(positions), rcond=None)
    dissipated, work = np.array(energies[1]) - np.array(energies[0])
    return (math.hypot(a, b), math.atan2(b, a)), dissipated, work, h


def test_a_harmonic_force_held_over_each_step_gives_the_closed_form_response_half_a_step_late(test_fmu):
    # A force F sin(w t) on the damped bob, r = w / W0 below, at and above resonance, drives it in
    # steady state to X sin(w t + phi), X = F / K / sqrt((1 - r^2)^2 + (2 ZETA r)^2),
    # phi = -atan2(2 ZETA r, 1 - r^2). The master sets the force at each point and the FMU holds it
    # over the step (docs/fmu.md): a staircase whose component at w is F sinc(w h / 2) sin(w (t -
    # h / 2)), so the response is the closed form's with that amplitude and half a step late, and
    # tends to the closed form as h shrinks, its phase at first order, its amplitude at second
    # (32 and 64 steps a period at resonance). What the staircase's harmonics at 2 pi k / h +- w
    # alias onto w at the points, and the integration error at rtol 1e-10, leave the amplitude
    # within 1.3e-6 of it and the phase within 2.6e-6 rad (measured): 1e-5. Over a period the
    # force does the work the damper dissipates, pi DAMPING w X^2 with the staircase's amplitude
    # (measured to 1.3e-6: 1e-5), and energy.input and energy.dissipated agree over it to the
    # integration's accuracy (measured 7e-8: 1e-6).
    F = 5.0
    fmu = test_fmu("driven_oscillator")
    for r, steps in ((0.5, 64), (1.0, 32), (1.0, 64), (2.0, 64)):
        w = r * W0

        def push(inst, t, h):
            inst.set("tip.fx", F * math.sin(w * t))

        (amplitude, phase), dissipated, work, h = steady_harmonic_response(fmu, push, w, steps)
        held = math.sin(w * h / 2) / (w * h / 2)
        X = held * F / K / math.hypot(1 - r * r, 2 * ZETA * r)
        phi = -math.atan2(2 * ZETA * r, 1 - r * r)
        assert amplitude == pytest.approx(X, rel=1e-5), (r, steps)
        assert phase == pytest.approx(phi - w * h / 2, abs=1e-5), (r, steps)
        assert work == pytest.approx(math.pi * DAMPING * w * X * X, rel=1e-5), (r, steps)
        assert work == pytest.approx(dissipated, rel=1e-6), (r, steps)


@pytest.mark.parametrize("input_changes", ["restart", "keep"])
def test_an_undamped_oscillator_forced_at_every_point_keeps_its_energy(test_fmu, input_changes):
    # The undamped driven oscillator (d = 0) under 0.1 sin(t) N set at every 1 ms point for 10 s,
    # against the exact response to the force held over each step. Each point's jump, at most
    # 1e-4 N, changes the 2 kg bob's velocity by 5e-8 m/s over the step, within the velocity
    # tolerance (1e-6 m/s): CVODE's history carries it under the default too, no restart.
    # Restarting at every point, as every changed input did before, started BDF again at first
    # order each time, about rtol of the motion lost per restart: 6.0e-3 m off (3 % of the 0.2 m
    # swing) and 6.1 % of the energy gone (measured). With the history: 1.8e-6 m off, and
    # kinetic + elastic - input energy stays at its 1 J within 6.3e-7 J (measured; rtol 1e-6, so
    # 2e-5 m and 1e-5 J). solver.input_changes reads back what was set, "restart" by default.
    inst = Instance(test_fmu("driven_oscillator"), logging_on=True)
    s, h, steps = inst.slave, 1e-3, 10000
    try:
        inst.start({"d": 0.0, **({"solver.input_changes": "keep"} if input_changes == "keep" else {})})
        assert s.getString([inst.vr["solver.input_changes"]]) == [input_changes.encode()]
        for k in range(steps):
            inst.set("tip.fx", 0.1 * math.sin(k * h))
            s.doStep(k * h, h)
        x, _ = undamped_response_to_held_forces([0.1 * math.sin(k * h) for k in range(steps)], h)
        kinetic, elastic, work = inst.get("energy.kinetic", "energy.elastic", "energy.input")
        restarts = [int(re.search(r"(\d+) restarts", m[2]).group(1)) for m in inst.messages if m[1] == "logSolver"]
        assert abs(inst.get("tip.x") - x) < 2e-5 and abs(kinetic + elastic - work - 1.0) < 1e-5
        assert len(restarts) == steps and sum(restarts) == 0
    finally:
        inst.free()


def test_a_base_accelerated_at_every_point_keeps_the_history_and_the_energy(test_fmu):
    # The undamped driven oscillator's base moved through samples every 1 ms, as a master with the
    # acceleration's samples gives it: at each point the position and velocity its path has reached
    # and, as the velocity's derivative, the acceleration -0.18 sin(3 t) m/s^2 at the middle of the
    # coming step. Each point turns the base's path along its velocity: CVODE keeps its history (no
    # restart after the first step, which sets the base moving). Exactly, interval by interval,
    # z = x_bob - x_base - 0.5 m obeys z'' = -w^2 z - a (w^2 = 25 /s^2), so z + a / w^2 turns by
    # w h in its phase plane. Measured over 2 s at rtol 1e-6: 1.0e-7 m off, and kinetic + elastic -
    # input energy 7.7e-7 J off its 1 J; restarted at each point (as while the driver's whole power
    # was integrated, which such a turn makes jump): 1.2e-3 m and 1.2e-2 J. Asserted: 1e-6 m and
    # 1e-5 J (rtol 1e-6 of the 1 J).
    inst = Instance(test_fmu("driven_oscillator"), logging_on=True)
    s, h, steps, w = inst.slave, 1e-3, 2000, 5.0
    x, v, z, zv = 0.0, 0.06, 0.2, -0.06
    worst_x, worst_balance = 0.0, 0.0
    try:
        inst.start({"d": 0.0})
        for k in range(steps):
            a = -0.18 * math.sin(3.0 * (k + 0.5) * h)
            inst.set("base.x", x)
            inst.set("base.vx", v)
            s.setRealInputDerivatives([inst.vr["base.vx"]], [1], [a])
            s.doStep(k * h, h)
            shifted = z + a / (w * w)
            z, zv = shifted * math.cos(w * h) + zv / w * math.sin(w * h) - a / (w * w), \
                -shifted * w * math.sin(w * h) + zv * math.cos(w * h)
            x, v = x + h * (v + 0.5 * h * a), v + h * a
            kinetic, elastic, work = inst.get("energy.kinetic", "energy.elastic", "energy.input")
            worst_x = max(worst_x, abs(inst.get("tip.x") - (x + 0.5 + z)))
            worst_balance = max(worst_balance, abs(kinetic + elastic - work - 1.0))
        restarts = [int(re.search(r"(\d+) restarts", m[2]).group(1)) for m in inst.messages if m[1] == "logSolver"]
        print(f"|x - exact| = {worst_x:.3g} m, |balance - 1 J| = {worst_balance:.3g} J, restarts {sum(restarts[1:])}")
        assert worst_x < 1e-6 and worst_balance < 1e-5
        assert len(restarts) == steps and sum(restarts[1:]) == 0
    finally:
        inst.free()


def test_a_base_moved_harmonically_through_the_motion_port_gives_the_closed_form_transmissibility(test_fmu):
    # Base excitation: the anchor moves as Y sin(w t), r = w / W0 below, at and above resonance,
    # and the damped bob follows in steady state as Y T sin(w t + psi), with the transmissibility
    # T = sqrt(1 + (2 ZETA r)^2) / sqrt((1 - r^2)^2 + (2 ZETA r)^2) and
    # psi = -atan2(2 ZETA r^3, 1 - r^2 + (2 ZETA r)^2). The master gives at each point the base's
    # position and the velocity that takes it to the next one, which the FMU holds over the step
    # (docs/fmu.md): the base moves along the broken line through the sine's points, whose
    # component at w is Y sinc(w h / 2)^2 sin(w t), so the response is the closed form's with that
    # amplitude and no lag, and tends to the closed form at second order as h shrinks (32 and 64
    # steps a period at resonance). The aliased harmonics and the integration error leave the
    # amplitude within 1.1e-6 of it (measured), and the phase as close: 1e-5. At every point the
    # force on the base is what its spring and damper carry, from the same state: round-off of
    # forces of 20 N (measured 3.6e-15 N), 1e-12 N. Over a period the mechanical energy comes
    # back, so the base's driver does the work the damper dissipates: energy.input and
    # energy.dissipated agree over it to the integration's accuracy (measured 5.8e-7: 1e-5).
    Y = 0.1
    fmu = test_fmu("driven_oscillator")
    for r, steps in ((0.5, 64), (1.0, 32), (1.0, 64), (2.0, 64)):
        w = r * W0
        worst_force = 0.0

        def shake(inst, t, h):
            nonlocal worst_force
            x, x_next = Y * math.sin(w * t), Y * math.sin(w * (t + h))
            inst.set("base.x", x)
            inst.set("base.vx", (x_next - x) / h)
            base_x, base_vx, x, v, force = inst.get("p[0].x", "p[0].vx", "tip.x", "tip.vx", "base.fx")
            worst_force = max(worst_force, abs(force - (K * (x - base_x - L0) + DAMPING * (v - base_vx))))

        (amplitude, phase), dissipated, work, h = steady_harmonic_response(fmu, shake, w, steps)
        line = (math.sin(w * h / 2) / (w * h / 2)) ** 2
        transmissibility = math.hypot(1, 2 * ZETA * r) / math.hypot(1 - r * r, 2 * ZETA * r)
        psi = -math.atan2(2 * ZETA * r**3, 1 - r * r + (2 * ZETA * r) ** 2)
        assert amplitude == pytest.approx(line * Y * transmissibility, rel=1e-5), (r, steps)
        assert phase == pytest.approx(psi, abs=1e-5), (r, steps)
        assert worst_force < 1e-12, (r, steps)
        assert work == pytest.approx(dissipated, rel=1e-5), (r, steps)


def test_input_derivatives_are_part_of_the_fmu_state(test_fmu):
    # A state saved mid-ramp and restored (also from bytes, into another instance) goes on along
    # the ramp and the acceleration: the same outputs both ways, and within the tolerances of the
    # run that went on without a restart (rtol 1e-10: 1e-8 m and m/s, K times that for the
    # force). fmi2Reset clears the derivatives:
    # the run is then that of a fresh instance, bit for bit.
    names = ("tip.x", "tip.vx", "base.fx")
    inst = Instance(test_fmu("driven_oscillator")).start(TIGHT)
    other = Instance(test_fmu("driven_oscillator")).start(TIGHT)
    fresh = Instance(test_fmu("driven_oscillator")).start(TIGHT)
    try:
        s, vr = inst.slave, inst.vr
        s.setRealInputDerivatives([vr["tip.fx"], vr["base.vx"]], [1, 1], [2.0, -0.5])
        for n in range(3):
            s.doStep(n * 0.1, 0.1)
        saved = s.getFMUstate()
        blob = s.serializeFMUstate(saved)
        for n in range(3, 10):
            s.doStep(n * 0.1, 0.1)
        through = inst.get(*names)
        s.setFMUstate(saved)
        for n in range(3, 10):
            s.doStep(n * 0.1, 0.1)
        restored = inst.get(*names)
        other.slave.setFMUstate(other.slave.deSerializeFMUstate(blob))
        for n in range(3, 10):
            other.slave.doStep(n * 0.1, 0.1)
        assert other.get(*names) == restored
        # Measured 2.3e-10 m, 1.8e-9 m/s and K times the first, 1.2e-8 N.
        assert np.all(np.abs(np.array(restored) - through) < [1e-8, 1e-8, K * 1e-8]), (restored, through)
        s.freeFMUstate(saved)
        s.reset()
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        for name, value in TIGHT.items():
            inst.set(name, value)
        s.exitInitializationMode()
        for n in range(10):
            s.doStep(n * 0.1, 0.1)
            fresh.slave.doStep(n * 0.1, 0.1)
        assert inst.get(*names) == fresh.get(*names)
    finally:
        inst.free()
        other.free()
        fresh.free()


def test_run_with_input_signals_agrees_with_the_fmu_given_their_derivatives(test_fmu, tmp_path):
    # Piecewise-linear signals with a jump (a repeated time) and a hold after the last row, for the
    # force port and the motion port's positions: `run --input` against the model's FMU driven by
    # fmpy, which sets each input's value and its slope (fmi2SetRealInputDerivatives; a motion
    # port's velocity is the positions' slope) at communication points every 0.1 s, the row times
    # among them. The same inputs, integrated apart at rtol 1e-10: within 1e-8 m (K times that
    # for the force). The inputs' work agrees too, the inputs at t = 0 being the initial ones in
    # both (run's first row; the FMU's in initialisation mode, as fmpy's simulate_fmu gives them):
    # within 1e-7 J (forces up to 15 N times the state's 1e-8 m; measured 1.1e-8 J), but at the rows where
    # the anchor's velocity jumps (0.5, 1.2 and 1.6 s): run's row shows the state after the jump,
    # fmpy's before it, and the work differs by the anchor's kinetic energy's jump. It closes the
    # energy balance in both, which without it would be off by up to 1.7 J, to the same 1e-7 J.
    rows = [(0.0, 0.0, 0.0), (0.5, 2.0, 0.1), (0.5, -1.0, 0.1), (1.2, 1.0, -0.2), (1.6, 1.0, 0.0)]
    signals = tmp_path / "signals.csv"
    signals.write_text("time,tip.fx,base.x\n" + "".join(f"{t},{f},{x}\n" for t, f, x in rows))
    ran = tmp_path / "run.csv"
    subprocess.run([str(CLI), "run", str(MODELS / "driven_oscillator.json"), "-q", "-o", str(ran), "--input",
                    str(signals), "--rtol", "1e-10", "--atol", "1e-12", "--t-end", "2", "--output-interval", "0.1"],
                   check=True)
    ran = np.genfromtxt(ran, delimiter=",", names=True)  # names without their dots: tipx
    def course(t, column):
        # The value in force at t (the later row of a repeated time) and the slope until the next.
        k = max(i for i, r in enumerate(rows) if r[0] <= t + 1e-12)
        if k + 1 == len(rows):
            return rows[k][column], 0.0
        slope = (rows[k + 1][column] - rows[k][column]) / (rows[k + 1][0] - rows[k][0])
        return rows[k][column] + slope * (t - rows[k][0]), slope

    (f, _), (x, dx) = course(0.0, 1), course(0.0, 2)
    inst = Instance(test_fmu("driven_oscillator")).start({"solver.rtol": 1e-10, "solver.atol_position": 1e-12,
                                                         "solver.atol_velocity": 1e-12, "tip.fx": f,
                                                         "base.x": x, "base.vx": dx})
    slave, vr = inst.slave, inst.vr
    names = ["tip.x", "base.fx", "energy.kinetic", "energy.elastic", "energy.dissipated", "energy.input"]
    try:
        got = [slave.getReal([vr[n] for n in names])]
        for n in range(20):
            t = n * 0.1
            (f, df), (x, dx) = course(t, 1), course(t, 2)
            slave.setReal([vr["tip.fx"], vr["base.x"], vr["base.vx"]], [f, x, dx])
            slave.setRealInputDerivatives([vr["tip.fx"]], [1], [df])
            slave.doStep(t, 0.1)
            got.append(slave.getReal([vr[n] for n in names]))
    finally:
        inst.free()
    got = np.array(got)
    assert np.max(np.abs(ran["tipx"] - got[:, 0])) < 1e-8
    assert np.max(np.abs(ran["basefx"] - got[:, 1])) < K * 1e-8
    jumps = np.isin(np.round(ran["time"], 9), [0.5, 1.2, 1.6])
    assert np.max(np.abs(ran["energyinput"] - got[:, 5])[~jumps]) < 1e-7
    assert np.all(np.abs(ran["energyinput"] - got[:, 5])[jumps] > 0.01)
    assert np.max(np.abs(got[:, 5])) > 1.0
    for balance in (ran["energykinetic"] + ran["energyelastic"] + ran["energydissipated"] - ran["energyinput"],
                    got[:, 2] + got[:, 3] + got[:, 4] - got[:, 5]):
        assert np.max(np.abs(balance - balance[0])) < 1e-7, np.max(np.abs(balance - balance[0]))


def test_run_given_positions_and_velocities_agrees_with_the_fmu_given_the_velocities_slopes(test_fmu, tmp_path):
    # README: `run --input` given a motion port's positions and velocities sets the port at each
    # row's position and velocity and accelerates it at the velocities' slope to the next row; an
    # FMU given the same values at communication points on the rows holds the velocity over the
    # step, and moves as run does only when the master passes those slopes on as the velocities'
    # derivatives. The rows: the anchor along 0.1 sin(2 pi t) m, every 0.05 s, with its velocity
    # (not the positions' slope). Integrated apart at rtol 1e-10: within 1e-8 m, as above
    # (measured 3e-14 m); held alone, the velocities miss the anchor's acceleration of up to
    # 4 m/s^2 over each 0.05 s step, up to 5 mm of its path, which the bob follows (measured 5.6 mm).
    h = 0.05
    times = [h * n for n in range(41)]
    x = [0.1 * math.sin(2 * math.pi * t) for t in times]
    v = [0.2 * math.pi * math.cos(2 * math.pi * t) for t in times]
    signals = tmp_path / "signals.csv"
    signals.write_text("time,base.x,base.vx\n" + "".join(f"{t!r},{a!r},{b!r}\n" for t, a, b in zip(times, x, v)))
    ran = tmp_path / "run.csv"
    subprocess.run([str(CLI), "run", str(MODELS / "driven_oscillator.json"), "-q", "-o", str(ran), "--input",
                    str(signals), "--rtol", "1e-10", "--atol", "1e-12", "--t-end", "2", "--output-interval", str(h)],
                   check=True)
    ran = np.genfromtxt(ran, delimiter=",", names=True)
    tips = []
    for derivatives in (True, False):
        inst = Instance(test_fmu("driven_oscillator")).start({"solver.rtol": 1e-10, "solver.atol_position": 1e-12,
                                                             "solver.atol_velocity": 1e-12, "base.x": x[0],
                                                             "base.vx": v[0]})
        slave, vr = inst.slave, inst.vr
        try:
            tip = [inst.get("tip.x")]
            for n in range(40):
                slave.setReal([vr["base.x"], vr["base.vx"]], [x[n], v[n]])
                if derivatives:
                    slave.setRealInputDerivatives([vr["base.vx"]], [1], [(v[n + 1] - v[n]) / h])
                slave.doStep(times[n], h)
                tip.append(inst.get("tip.x"))
        finally:
            inst.free()
        tips.append(np.array(tip))
    assert np.max(np.abs(ran["tipx"] - tips[0])) < 1e-8
    assert np.max(np.abs(ran["tipx"] - tips[1])) > 1e-3


def test_a_force_input_acts_along_each_of_its_components(test_fmu):
    # A force (Fx, Fy, Fz) on the bob at rest, 0.2 m stretched along x: over a short step h the
    # velocity changes by (F + f_spring) h / m, the spring pulling along x only (-k 0.2 = -10 N);
    # the spring's turning as the bob moves adds terms of relative size (k/m) h^2 = 2.5e-5 at
    # h = 1 ms: 1e-4 relative to each component's prediction.
    inst = Instance(test_fmu("driven_oscillator")).start({"solver.rtol": 1e-10})
    try:
        force = (1.5, -2.0, 3.0)
        for name, value in zip(("tip.fx", "tip.fy", "tip.fz"), force):
            inst.set(name, value)
        h = 1e-3
        inst.slave.doStep(0.0, h)
        v = inst.get("tip.vx", "tip.vy", "tip.vz")
        expected = [(force[0] - K * (X0 - L0)) * h / M, force[1] * h / M, force[2] * h / M]
        for got, want in zip(v, expected):
            assert abs(got - want) <= 1e-4 * abs(want), (v, expected)
    finally:
        inst.free()


def test_inputs_set_in_initialisation_do_no_work_and_those_after_do(test_fmu):
    # Inputs set in initialisation mode give the initial state, also after a value was read there
    # (which creates the simulation and gives it the inputs set so far): energy.input stays 0. The
    # same move of the anchor after initialisation does the work of the energy it adds, at once:
    # moved from 0.1 m to 0.2 m and stopped, it lets the spring (to the bob at 0.7 m) relax from
    # 0.1 m beyond its rest length to none, -k 0.1^2 / 2, and loses its own kinetic energy,
    # -m 0.5^2 / 2 (1 kg): -0.375 J, to round-off. The push on the bob then works as it moves, closing the balance:
    # kinetic + elastic + dissipated - input stays at its value after the move (rtol 1e-10 over
    # 0.5 s on energies of 1 J: within 1e-8 J).
    inst = Instance(test_fmu("driven_oscillator"))
    try:
        s = inst.slave
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        for name, value in TIGHT.items():
            inst.set(name, value)
        assert inst.get("energy.input") == 0.0
        inst.set("base.x", 0.1)
        inst.set("base.vx", 0.5)
        assert inst.get("energy.input") == 0.0
        # Its derivative with respect to a motion input is 0 there, and after initialisation that
        # of the energy a move adds: the spring (0.6 m, rest length 0.5 m) relaxes as the anchor
        # moves towards the bob, -k 0.1 m.
        vr = [inst.vr["energy.input"]], [inst.vr["base.x"]]
        assert s.getDirectionalDerivative(*vr, [1.0]) == [0.0]
        s.exitInitializationMode()
        assert inst.get("energy.input") == 0.0
        assert abs(s.getDirectionalDerivative(*vr, [1.0])[0] - (-K * (0.7 - 0.1 - 0.5))) < 1e-12
        inst.set("base.vx", 0.0)
        inst.set("base.x", 0.2)
        moved = inst.get("energy.input")
        assert abs(moved - (-0.5 * K * 0.1 ** 2 - 0.5 * 1.0 * 0.5 ** 2)) < 1e-15, moved
        inst.set("tip.fx", 3.0)
        names = ("energy.kinetic", "energy.elastic", "energy.dissipated", "energy.input")
        start = sum(np.array(inst.get(*names)) * [1, 1, 1, -1])
        for n in range(5):
            s.doStep(0.1 * n, 0.1)
            assert abs(sum(np.array(inst.get(*names)) * [1, 1, 1, -1]) - start) < 1e-8
        assert inst.get("energy.input") - moved > 0.1
    finally:
        inst.free()


def test_a_tunable_parameter_set_between_steps_does_the_work_of_the_energy_it_adds(test_fmu):
    # Doubling k between steps doubles the spring's elastic energy at once, as a motion input set
    # there changes it: whatever sets the parameter does that work, so that the balance kinetic +
    # elastic + dissipated - input holds across the set to round-off and after it to the
    # tolerances (rtol 1e-10 over 0.5 s on energies of 1 J, the spring now twice as stiff: within
    # 1e-7 J, measured 4.0e-8 J). Without the work it
    # would be off by the spring's energy before the set, 0.84 J here. A second set, k back to its
    # value, adds its work to the first's: the balance still holds across it.
    inst = Instance(test_fmu("driven_oscillator")).start(TIGHT)
    names = ("energy.kinetic", "energy.elastic", "energy.dissipated", "energy.input")
    # The variable's description says so, beside the ports whose work it counts.
    assert inst.variables["energy.input"].description == (
        "work done by the inputs since the start (force ports on free particles, motion ports, "
        "tunable parameters set between steps)")
    try:
        s = inst.slave
        inst.set("tip.fx", 3.0)
        start = sum(np.array(inst.get(*names)) * [1, 1, 1, -1])
        s.doStep(0.0, 0.1)
        elastic = inst.get("energy.elastic")
        inst.set("k", 2 * K)
        assert abs(inst.get("energy.elastic") - 2 * elastic) < 1e-15 and elastic > 0.1
        assert abs(sum(np.array(inst.get(*names)) * [1, 1, 1, -1]) - start) < 1e-8
        for n in range(1, 5):
            s.doStep(0.1 * n, 0.1)
            assert abs(sum(np.array(inst.get(*names)) * [1, 1, 1, -1]) - start) < 1e-7
        inst.set("k", K)
        assert abs(sum(np.array(inst.get(*names)) * [1, 1, 1, -1]) - start) < 1e-7
    finally:
        inst.free()


LOADED = {
    "springmass": 1, "name": "loaded", "parameters": {"F": 1.0}, "gravity": [0, 0, 0],
    "particles": [{"name": "anchor", "position": [0, 0, 0], "fixed": True},
                  {"name": "bob", "position": [1.0, 0, 0], "mass": 1.0}],
    "springs": [{"a": "anchor", "b": "bob", "stiffness": 40.0, "rest_length": 1.0}],
    "loads": [{"particle": "bob", "force": ["F", 0, 0]}],
    "ports": [{"name": "tip", "particle": "bob", "kind": "probe"}]}


def test_a_load_parameter_is_tunable_and_its_potential_counts(package, tmp_path):
    # A load from the model file pulls the bob from rest: x = 1 + F / k (1 - cos w t). F is a tunable
    # parameter in N; set to 3 N between steps, the bob swings about its new rest point 1 + 3 / k
    # from where it is. The load is the model's, not an input: its potential -F x is part of
    # energy.gravity, and the energy the new value adds at once (-2 N times x) counts in
    # energy.input as a tunable parameter's does, so that the balance holds across the set to
    # round-off and after it to the tolerances (rtol 1e-10: 1e-7 J asserted, as above). Positions
    # to 1e-7 m (the closed forms' error at rtol 1e-10 over 0.7 s is about 1e-9 m).
    model = tmp_path / "loaded.json"
    model.write_text(json.dumps(LOADED))
    inst = Instance(package(model)).start(TIGHT)
    names = ("energy.kinetic", "energy.elastic", "energy.gravity", "energy.dissipated", "energy.input")
    weights = [1, 1, 1, 1, -1]
    assert inst.variables["F"].variability == "tunable" and inst.variables["F"].unit == "N"
    try:
        k, w, t1 = 40.0, math.sqrt(40.0), 0.3
        start = sum(np.array(inst.get(*names)) * weights)
        assert inst.get("energy.gravity") == -1.0
        inst.slave.doStep(0.0, t1)
        x1, v1 = 1 + 1.0 / k * (1 - math.cos(w * t1)), 1.0 / k * w * math.sin(w * t1)
        assert abs(inst.get("tip.x") - x1) < 1e-7 and abs(inst.get("tip.vx") - v1) < 1e-7
        inst.set("F", 3.0)
        assert abs(inst.get("energy.gravity") + 3.0 * inst.get("tip.x")) < 1e-15
        assert abs(sum(np.array(inst.get(*names)) * weights) - start) < 1e-8
        inst.slave.doStep(t1, 0.4)
        rest = 1 + 3.0 / k
        x = rest + (x1 - rest) * math.cos(w * 0.4) + v1 / w * math.sin(w * 0.4)
        assert abs(inst.get("tip.x") - x) < 1e-7
        assert abs(sum(np.array(inst.get(*names)) * weights) - start) < 1e-7
    finally:
        inst.free()


LOADED_HOOK = {
    "springmass": 1, "name": "loaded_hook", "gravity": [0, 0, -9.81],
    "particles": [{"name": "hook", "position": [0, 0, 0], "mass": 0.1, "fixed": True},
                  {"name": "bob", "position": [0, 0, -0.3], "mass": 0.5}],
    "springs": [{"a": "hook", "b": "bob", "stiffness": 200.0, "rest_length": 0.3}],
    "loads": [{"particle": "hook", "force": [1.5, -2.0, 3.0]}],
    "ports": [{"name": "hook", "particle": "hook", "kind": "motion"}]}


def test_directional_derivative_of_the_potential_of_a_load_on_a_driven_particle(package, tmp_path):
    # A load on a driven particle is part of the model (docs/model-format.md, Loads: on a
    # constrained particle it goes to the reaction) and its potential -F . x part of
    # energy.gravity: E_g = -(m_hook g + F) . x_hook - m_bob g . x_bob. Moving the hook by a seed
    # dx therefore changes energy.gravity by -(m_hook g + F) . dx, a closed form, and the inputs'
    # work by the change of the three energies (as the moving damped system above). E_g is linear
    # in x_hook, so a central difference with h = 1e-6 m is exact but for the round-off of
    # energies of order 1 J over 2h, about 1e-10: 1e-9 asserted for the closed form, rtol and
    # atol 1e-7 against the differences (the elastic energy's h^2 truncation is ~1e-10 J/m).
    model = tmp_path / "loaded_hook.json"
    model.write_text(json.dumps(LOADED_HOOK))
    inst = Instance(package(model)).start()
    try:
        s, vr = inst.slave, inst.vr
        constant = 0.1 * np.array([0.0, 0.0, -9.81]) + np.array([1.5, -2.0, 3.0])
        # At the start the spring is at its rest length: the force on the hook, which the port
        # gives to whatever drives it, is its weight and its load alone (sums of doubles near 1).
        force = np.array(s.getReal([vr[n] for n in ("hook.fx", "hook.fy", "hook.fz")]))
        assert np.allclose(force, constant, rtol=0.0, atol=1e-15), force
        known = [vr[n] for n in ("hook.x", "hook.y", "hook.z")]
        x = np.array([0.05, -0.02, 0.04])
        s.setReal(known, list(x))
        names = ["energy.gravity", "energy.elastic", "energy.kinetic", "energy.input"]
        unknown = [vr[n] for n in names]
        seed = np.array([0.7, 1.3, -0.4])
        analytic = np.array(s.getDirectionalDerivative(unknown, known, list(seed)))
        assert abs(analytic[0] - (-constant @ seed)) < 1e-9, (analytic[0], -constant @ seed)
        fd = central_difference(s, unknown, known, x, seed)
        assert np.allclose(analytic, fd, rtol=1e-7, atol=1e-7), list(zip(names, analytic, fd))
    finally:
        inst.free()


def test_a_motion_input_set_in_a_step_applies_from_its_start_changed_or_not(test_fmu):
    # A motion port set in a communication step moves from P.x with P.vx from the step's start.
    # The master holds base.x = 0 and base.vx = 1 m/s at every 0.1 s step, so the anchor is at
    # 0.1 m after each, whether base.x is sent as 0 every time or alternates between 0 and the
    # smallest subnormal (a change that must not matter). A step without a set keeps the motion:
    # 0.2 m after it. Tolerance: the step length (t_n + h) - t_n is h to the round-off of t < 1 s
    # (ulp 1.1e-16 s), times 1 m/s.
    for wiggle in (False, True):
        inst = Instance(test_fmu("driven_oscillator")).start()
        try:
            for n in range(5):
                inst.set("base.x", 5e-324 if wiggle and n % 2 else 0.0)
                inst.set("base.vx", 1.0)
                inst.slave.doStep(0.1 * n, 0.1)
                assert abs(inst.get("p[0].x") - 0.1) < 1e-15, (wiggle, n, inst.get("p[0].x"))
            inst.slave.doStep(0.5, 0.1)
            assert abs(inst.get("p[0].x") - 0.2) < 1e-15
        finally:
            inst.free()


def test_tunable_parameter_between_steps(test_fmu):
    # Changing k between steps takes effect from that point on, with the state kept: after the
    # change at t1 the bob oscillates with the new frequency about the same rest length.
    inst = Instance(test_fmu("driven_oscillator")).start(
        {"solver.rtol": 1e-10, "solver.atol_position": 1e-12, "solver.atol_velocity": 1e-10})
    assert inst.variables["k"].variability == "tunable"
    try:
        w1, w2, t1 = math.sqrt(K / M), math.sqrt(4 * K / M), 0.3
        inst.slave.doStep(0.0, t1)
        x1 = L0 + (X0 - L0) * math.cos(w1 * t1)
        v1 = -(X0 - L0) * w1 * math.sin(w1 * t1)
        # The outputs follow the new value at once, before any step: the force on the anchor is
        # k (x - l0) at the same state, four times what it was (read first, so that it was known).
        force_before = inst.get("base.fx")
        assert abs(force_before - K * (x1 - L0)) < 1e-6
        inst.set("k", 4 * K)
        assert abs(inst.get("base.fx") - 4 * force_before) < 1e-12
        inst.slave.doStep(t1, 0.4)
        t = 0.4
        expected = L0 + (x1 - L0) * math.cos(w2 * t) + v1 / w2 * math.sin(w2 * t)
        assert abs(inst.get("tip.x") - expected) < 1e-6
    finally:
        inst.free()


def refused_as_fixed(inst, name, value):
    """Setting the fixed parameter `name` after initialisation fails with a message saying so."""
    with pytest.raises(FMICallException):
        inst.set(name, value)
    assert f"{name} is a fixed parameter" in inst.messages[-1][2]


def test_a_bound_of_held_particles_is_a_fixed_parameter(test_fmu):
    # box_param: a box holds the rope's particles at x <= xmax = 2 (all five); 3.5, the first
    # value tried, holds the same, but 0.6 frees rope[3] and rope[4], which a running simulation
    # cannot take. xmax is fixed, so 0.6 is taken before initialisation (the rope's end then falls)
    # and refused as a fixed parameter after it; k, which feeds stiffnesses only, stays tunable.
    fmu = test_fmu("box_param")
    inst = Instance(fmu)
    try:
        assert inst.variables["xmax"].variability == "fixed" and inst.variables["k"].variability == "tunable"
        assert inst.variables["xmax"].description == (
            "model-file parameter xmax (fixed: feeds which particles are held)")
        inst.start({"xmax": 0.6})
        inst.slave.doStep(0.0, 0.1)
        assert inst.get("p[4].z") < 0.0 and inst.get("p[3].z") == 0.0  # rope[3] falls, rope[2] is held
        refused_as_fixed(inst, "xmax", 2.0)
        inst.set("k", 50.0)
        inst.slave.doStep(0.1, 0.1)
    finally:
        inst.free()


def test_a_bound_that_holds_the_same_particles_at_many_values_is_still_fixed(test_fmu):
    # far_box: the box holds the anchor (x = 0) for xmax from 0 to 5000 and the bob (x = 5000)
    # from there on, so that every value from half to double and a thousand times the scale up
    # holds the same particle; xmax feeds which particles are held all the same, so it is fixed:
    # 6000 (both held) is taken before initialisation and refused after it.
    fmu = test_fmu("far_box")
    inst = Instance(fmu)
    try:
        assert inst.variables["xmax"].variability == "fixed" and inst.variables["k"].variability == "tunable"
        inst.start({"xmax": 6000.0})
        inst.slave.doStep(0.0, 0.1)
        assert inst.get("tip.x") == 5000.0 and inst.get("tip.z") == 0.0  # the bob is held too
        refused_as_fixed(inst, "xmax", 2.0)
    finally:
        inst.free()


def test_a_rest_length_that_chooses_the_spring_law_is_fixed(test_fmu):
    # spring_law: the first spring has no kind, so its rest length L = 0 would make it a
    # zero-length spring, which a running simulation cannot take: L is fixed (0 is taken before
    # initialisation, refused after it). The second spring's kind is given: L2 is a constant of
    # the force law only and stays tunable.
    fmu = test_fmu("spring_law")
    inst = Instance(fmu)
    try:
        assert inst.variables["L"].variability == "fixed" and inst.variables["L2"].variability == "tunable"
        # Its description says what makes it fixed: the spring's kind, not a state it does not feed.
        assert inst.variables["L"].description == (
            "model-file parameter L (fixed: feeds a spring's kind (rest length 0 or not))")
        inst.start({"L": 0.0})
        # Taken: the first spring is zero-length, 50 (0.5)^2 / 2 = 6.25 J at the start, the
        # second at its rest length (one multiplication each: 1e-12 J).
        assert inst.get("L") == 0.0 and abs(inst.get("energy.elastic") - 6.25) < 1e-12
        inst.slave.doStep(0.0, 0.1)
        refused_as_fixed(inst, "L", 0.5)
        inst.set("L2", 0.3)

        def elastic(l2):
            d = np.linalg.norm(inst.get("tip.x", "tip.y", "tip.z"))
            return 0.5 * 50.0 * d * d + 0.5 * 50.0 * (d - l2) ** 2

        # Taken at once, the running simulation's state kept: the energy is that of the new rest
        # length at the bob's position (round-off of a few terms: 1e-12 J).
        assert inst.get("L2") == 0.3 and abs(inst.get("energy.elastic") - elastic(0.3)) < 1e-12
        inst.slave.doStep(0.1, 0.1)
    finally:
        inst.free()


def test_tunable_parameters_that_empty_a_spring_group():
    # The rope's springs take their constants from E and c, both tunable: set to 0 together
    # between steps, the springs stay (the topology cannot change) but pull nothing, so without
    # mass damping the tip falls freely from where it was: z = z1 + vz1 t - g t^2 / 2, which BDF
    # integrates exactly up to the tolerances (rtol 1e-10). Set back, the rope pulls again.
    inst = Instance(BUNDLED_FMUS / "hanging_rope.fmu").start(
        {"alpha": 0.0, "solver.rtol": 1e-10, "solver.atol_position": 1e-12, "solver.atol_velocity": 1e-10})
    try:
        inst.slave.doStep(0.0, 0.2)
        inst.slave.setReal([inst.vr["E"], inst.vr["c"]], [0.0, 0.0])
        z1, vz1 = inst.get("tip.z", "tip.vz")
        inst.slave.doStep(0.2, 0.1)
        assert inst.get("energy.elastic") == 0.0
        assert abs(inst.get("tip.z") - (z1 + vz1 * 0.1 - 9.81 * 0.1**2 / 2)) < 1e-8
        inst.slave.setReal([inst.vr["E"], inst.vr["c"]], [2000.0, 0.5])
        inst.slave.doStep(0.3, 0.1)
        assert inst.get("energy.elastic") > 0.0
    finally:
        inst.free()


def test_energy_balance_holds_across_saved_and_restored_states(test_fmu):
    # The damped oscillator (d = 0.5 N s/m, anchor held, no force) has no energy source: kinetic,
    # elastic and dissipated energy add up to the k (x0 - l0)^2 / 2 = 1 J it starts with, at every
    # step, after each fmi2GetFMUstate, after fmi2SetFMUstate of either of two states, and in
    # another instance given a state through its bytes: the dissipated energy is part of the state. rtol 1e-10: the three energies are
    # integrated to about 1e-8 J (measured 6.1e-9 J over 0.6 s): 1e-7 J.
    tight = {"d": 0.5, "solver.rtol": 1e-10, "solver.atol_position": 1e-12, "solver.atol_velocity": 1e-10}
    fmu = test_fmu("driven_oscillator")
    a, b = Instance(fmu, "a").start(tight), Instance(fmu, "b").start()
    names = ("energy.kinetic", "energy.elastic", "energy.dissipated")

    def balanced(inst, t0, steps):
        for n in range(steps):
            inst.slave.doStep(t0 + 0.02 * n, 0.02)
            assert abs(sum(inst.get(*names)) - 0.5 * K * (X0 - L0) ** 2) < 1e-7, (t0 + 0.02 * (n + 1), inst.get(*names))
        return inst.get("energy.dissipated")

    try:
        balanced(a, 0.0, 10)
        first = a.slave.getFMUstate()
        balanced(a, 0.2, 10)
        second = a.slave.getFMUstate()
        dissipated = balanced(a, 0.4, 10)
        assert dissipated > 0.1  # the damping has taken a good part of the joule
        a.slave.setFMUstate(first)
        balanced(a, 0.2, 20)
        a.slave.setFMUstate(second)
        restored = balanced(a, 0.4, 10)  # CVODE afresh from the state: to the balance's 1e-7 J
        assert restored == pytest.approx(dissipated, abs=1e-7)
        b.slave.setFMUstate(b.slave.deSerializeFMUstate(a.slave.serializeFMUstate(second)))
        assert balanced(b, 0.4, 10) == restored  # every restore alike, bit for bit
        a.slave.freeFMUstate(first)
        a.slave.freeFMUstate(second)
    finally:
        a.free()
        b.free()


BREAKING = {
    "springmass": 1, "name": "breaking", "description": "A bob pulled off its spring by a force port.",
    "gravity": [0, 0, 0], "mass_damping": 0.0,
    "particles": [{"name": "anchor", "position": [0, 0, 0], "fixed": True},
                  {"name": "bob", "position": [1, 0, 0], "mass": 1.0}],
    "springs": [{"a": "anchor", "b": "bob", "stiffness": 100.0, "rest_length": 1.0, "break_strain": 0.1}],
    "ports": [{"name": "tip", "particle": "bob", "kind": "force"}],
    "simulation": {"stop_time": 1.0, "output_interval": 0.01}}


def test_a_spring_breaks_when_its_closed_form_strain_reaches_the_limit(package, tmp_path):
    # A constant force F = 20 N on a bob of 1 kg at the end of a spring (k = 100 N/m, l0 = 1 m)
    # from rest: x - l0 = (F/k) (1 - cos(w t)), w = 10 rad/s, so the strain (x - l0) / l0 reaches
    # the break strain 0.1 at cos(w t) = 1/2, t_b = pi/30 s. The experiment starts at t = 5 s: the
    # logged time is 5 + t_b, found by root finding on a solution integrated at rtol 1e-10 (the
    # strain rises at 1.7 /s there; measured 7e-11 s off): 1e-8 s. The elastic energy the spring
    # held, k (0.1)^2 / 2 = 0.5 J, is dissipated, and then the bob accelerates freely: kinetic
    # energy is the work of F, F (x - x0), less the 0.5 J, to the integration's error on about
    # 2 J (measured 2.0e-9 J): 1e-7 J.
    model = tmp_path / "breaking.json"
    model.write_text(json.dumps(BREAKING))
    inst = Instance(package(model), logging_on=True).start(
        {"tip.fx": 20.0, "solver.rtol": 1e-10, "solver.atol_position": 1e-12, "solver.atol_velocity": 1e-10},
        start_time=5.0)
    try:
        for n in range(20):
            inst.slave.doStep(5.0 + 0.01 * n, 0.01)
        events = [m[2] for m in inst.messages if m[1] == "logEvents" and "broke" in m[2]]
        assert len(events) == 1 and "between anchor and bob" in events[0], events
        logged = float(events[0].split(":")[0].removeprefix("t = "))
        assert abs(logged - (5.0 + math.pi / 30)) < 1e-8, events
        kinetic, elastic, dissipated, x = inst.get("energy.kinetic", "energy.elastic", "energy.dissipated", "tip.x")
        assert elastic == 0.0 and abs(dissipated - 0.5) < 1e-7
        assert abs(kinetic - (20.0 * (x - 1.0) - 0.5)) < 1e-7
    finally:
        inst.free()


def test_a_break_names_a_particle_without_a_name_by_its_index(package, tmp_path):
    # The bob of the test above without a name (referred to as particle 1): logEvents names it as
    # the FMU's variables and `springmass run` do, by its index.
    unnamed = json.loads(json.dumps(BREAKING))
    del unnamed["particles"][1]["name"]
    unnamed["springs"][0]["b"] = unnamed["ports"][0]["particle"] = 1
    model = tmp_path / "breaking.json"
    model.write_text(json.dumps(unnamed))
    inst = Instance(package(model), logging_on=True).start({"tip.fx": 20.0})
    try:
        for n in range(20):
            inst.slave.doStep(0.01 * n, 0.01)
        events = [m[2] for m in inst.messages if m[1] == "logEvents" and "broke" in m[2]]
        assert len(events) == 1 and events[0].endswith(": spring 0 between anchor and particle 1 broke"), events
    finally:
        inst.free()


def test_a_break_is_logged_again_in_the_run_from_a_restored_state(package, tmp_path):
    # The bob of the test above, pulled by 20 N from rest, breaks its spring at t_b = pi/30 s. A
    # state saved at the start is the bob at rest on an intact spring: the run from it is the same
    # motion, and the spring breaks again at t_b, inside a step, which logEvents reports as it does
    # every break (to the same 1e-8 s as above). Restored twice, twice more, each logged once.
    model = tmp_path / "breaking.json"
    model.write_text(json.dumps(BREAKING))
    inst = Instance(package(model), logging_on=True).start(
        {"tip.fx": 20.0, "solver.rtol": 1e-10, "solver.atol_position": 1e-12, "solver.atol_velocity": 1e-10})
    try:
        state = inst.slave.getFMUstate()
        for run in range(3):
            if run > 0:
                inst.slave.setFMUstate(state)
            first = len(inst.messages)
            for n in range(20):
                inst.slave.doStep(0.01 * n, 0.01)
            events = [m[2] for m in inst.messages[first:] if m[1] == "logEvents" and "broke" in m[2]]
            assert len(events) == 1 and "between anchor and bob" in events[0], (run, events)
            logged = float(events[0].split(":")[0].removeprefix("t = "))
            assert abs(logged - math.pi / 30) < 1e-8, (run, events)
            assert inst.get("energy.elastic") == 0.0
        inst.slave.freeFMUstate(state)
    finally:
        inst.free()


def test_directional_derivative_of_a_compressed_spring(test_fmu):
    # The anchor moved to x = 0.4 m compresses the spring to L = 0.3 m < l0 = 0.5 m. Moving the
    # anchor sideways by dy turns the spring: the force on the anchor, k (L - l0) along the spring
    # towards the bob, gains a y-component -k (L - l0) dy / L, so d(base.fy)/d(base.y) =
    # -k (1 - l0/L) = +100/3 N/m (positive: a compressed spring pushes a sideways step further),
    # and along the spring -k = -50 N/m as ever. The analytic Jacobian is exact to round-off
    # (1e-12 relative; measured 4e-16); a central difference with h = 1e-6 m agrees to its h^2
    # term and the round-off of forces of 10 N over 2h (measured 1.4e-11 relative): 1e-6.
    inst = Instance(test_fmu("driven_oscillator")).start()
    try:
        s, vr = inst.slave, inst.vr
        inst.set("base.x", 0.4)
        k_yy = -K * (1.0 - L0 / 0.3)
        d = s.getDirectionalDerivative([vr["base.fy"], vr["base.fx"]], [vr["base.y"]], [1.0])
        assert abs(d[0] - k_yy) < 1e-12 * abs(k_yy) and d[1] == 0.0, d
        d = s.getDirectionalDerivative([vr["base.fx"]], [vr["base.x"]], [1.0])
        assert abs(d[0] + K) < 1e-12 * K, d
        h = 1e-6
        inst.set("base.y", h)
        up = inst.get("base.fy")
        inst.set("base.y", -h)
        down = inst.get("base.fy")
        assert abs((up - down) / (2 * h) - k_yy) < 1e-6 * abs(k_yy), ((up - down) / (2 * h), k_yy)
    finally:
        inst.free()


def test_a_motion_port_starts_with_its_particles_initial_motion(package, tmp_path):
    # A motion port's inputs start at its particle's initial position and velocity (the file's), so
    # that a master that never sets them sees the particle move from there along a straight line:
    # the hand from (1, 2, 3) at (0.5, 0, -0.25) m/s is at (1 + 0.5 t, 2, 3 - 0.25 t). Tolerance:
    # t is a sum of ten steps of 0.1 s, exact to a few ulps of 1 s (1e-15 m).
    model = tmp_path / "moving_hand.json"
    model.write_text(json.dumps({
        "springmass": 1, "name": "moving_hand", "description": "A hand that moves, a bob on a spring below.",
        "gravity": [0, 0, -9.81], "mass_damping": 0.0,
        "particles": [{"name": "hand", "position": [1, 2, 3], "velocity": [0.5, 0, -0.25], "mass": 1.0},
                      {"name": "bob", "position": [1, 2, 2], "mass": 1.0}],
        "springs": [{"a": "hand", "b": "bob", "stiffness": 100.0, "rest_length": 1.0}],
        "ports": [{"name": "hand", "particle": "hand", "kind": "motion"}],
        "simulation": {"stop_time": 1.0, "output_interval": 0.1}}))
    fmu = package(model)
    starts = {v.name: float(v.start) for v in read_model_description(str(fmu)).modelVariables
              if v.name.startswith("hand.") and v.causality == "input"}
    assert starts == {"hand.x": 1.0, "hand.y": 2.0, "hand.z": 3.0, "hand.vx": 0.5, "hand.vy": 0.0, "hand.vz": -0.25}
    inst = Instance(fmu).start()
    try:
        for n in range(10):
            inst.slave.doStep(0.1 * n, 0.1)
            t = 0.1 * (n + 1)
            assert np.allclose(inst.get("p[0].x", "p[0].y", "p[0].z"), [1 + 0.5 * t, 2.0, 3 - 0.25 * t],
                               rtol=0, atol=1e-15), (t, inst.get("p[0].x", "p[0].y", "p[0].z"))
        assert inst.get("hand.x", "hand.vx") == [1.0, 0.5]  # the inputs as they started
    finally:
        inst.free()


def test_solver_threads_change_nothing_in_the_results(package):
    # The bundled cloth at n = 64 (4094 free particles, over the 4000 from which the pcg solver's
    # loops run in chunks): solver.threads = 2 runs them on two threads, and every output and the
    # energies are the same, bit for bit, as with the default of one (the chunks, and the order of
    # every sum, depend on the model alone: docs/simulation.md). Inputs: none; three steps of 2 ms.
    # The two threads are there while the instance steps: the caller's and one started for it
    # (no more than the processors the process may run on), counted in /proc/self/task.
    fmu = package(ROOT / "models" / "cloth.json", ["n=64"])
    names = ["corner.x", "corner.z", "center.vz", "energy.elastic", "energy.dissipated"]
    process_threads = lambda: len(os.listdir("/proc/self/task"))
    results = []
    for threads in (1, 2):
        before = process_threads()
        inst = Instance(fmu, f"threads{threads}").start({"solver.threads": threads, "solver.linear_solver": "pcg"})
        try:
            assert inst.slave.getInteger([inst.vr["solver.threads"]]) == [threads]
            for k in range(3):
                inst.slave.doStep(0.002 * k, 0.002)
            results.append(inst.get(*names))
            started = min(threads, len(os.sched_getaffinity(0))) - 1
            assert process_threads() == before + started, (threads, before, process_threads())
        finally:
            inst.free()
    assert results[0] == results[1]
    assert results[0][1] < 0.0  # the cloth falls


def test_model_structure_lists_the_inputs_each_output_depends_on(test_fmu):
    # FMI 2.0 (2.2.8): an output's `dependencies` are the knowns it depends on directly, in
    # Co-Simulation its inputs, each named by its index in ModelVariables (1-based). docs/fmu.md
    # names them: a motion port's force depends on the prescribed positions and velocities of its
    # port and of the motion ports a spring joins it to, the kinetic energy on their velocities, the elastic and gravitational energies
    # on their positions (the gravitational energy on those along which the weight or a load can
    # pull), the inputs' work on all of these; a port's position and velocity and the dissipated
    # energy are states, with none. In driven_oscillator the motion port is "base" (the anchor,
    # mass 1 kg) and the force port "tip"; gravity is (0, 0, 0), a number, and there are no
    # loads: the gravitational energy is 0 wherever the anchor is, and depends on no input.
    fmu = test_fmu("driven_oscillator")
    md = read_model_description(str(fmu))
    variables = md.modelVariables
    inputs = {v.name for v in variables if v.causality == "input"}
    position = ["base.x", "base.y", "base.z"]
    velocity = ["base.vx", "base.vy", "base.vz"]
    expected = {f"base.f{c}": position + velocity for c in "xyz"}
    expected.update({f"tip.{c}": [] for c in ("x", "y", "z", "vx", "vy", "vz")})
    expected.update({"energy.kinetic": velocity, "energy.elastic": position, "energy.gravity": [],
                     "energy.dissipated": [], "energy.input": position + velocity})
    listed = listed_dependencies(fmu)
    assert listed == expected
    # The analytic derivatives at a moving, displaced anchor with spring damping d = 0.3 N s/m:
    # every input an output changes with is among its dependencies.
    inst = Instance(fmu).start(start_values={"d": 0.3})
    try:
        s, vr = inst.slave, inst.vr
        for name, value in {"base.x": 0.1, "base.y": 0.05, "base.vx": 0.2, "base.vy": 0.1, "tip.fx": 1.0}.items():
            inst.set(name, value)
        s.doStep(0.0, 0.01)
        for output, names in listed.items():
            for known in sorted(inputs):
                d = s.getDirectionalDerivative([vr[output]], [vr[known]], [1.0])[0]
                assert d == 0.0 or known in names, (output, known, d)
    finally:
        inst.free()


def listed_dependencies(fmu):
    """{output name: [input names]}, the Outputs' dependencies in the modelDescription.xml of fmu as
    written, after checking that each list is in ascending order, names each index once, and names
    inputs only."""
    variables = read_model_description(str(fmu)).modelVariables
    with zipfile.ZipFile(fmu) as archive:
        xml = archive.read("modelDescription.xml").decode("utf-8")
    outputs = re.search(r"<Outputs>(.*?)</Outputs>", xml, re.S).group(1)
    listed = {}
    for index, dependencies in re.findall(r'<Unknown index="(\d+)" dependencies="([\d ]*)"/>', outputs):
        indices = [int(k) for k in dependencies.split()]
        assert indices == sorted(set(indices)), (index, indices)
        output = variables[int(index) - 1]
        assert output.causality == "output", (index, output.name)
        assert all(variables[k - 1].causality == "input" for k in indices), (output.name, indices)
        listed[output.name] = [variables[k - 1].name for k in indices]
    return listed


def check_hooks_dependencies(fmu):
    """The ModelStructure of joined_hooks or crossed_hooks (motion ports a, b and c; springs join a
    to b and a to c, not b to c): every output's dependencies in ascending order, each once, and a
    port's force listing its own six inputs and those of the ports a spring joins it to, every
    spring having stiffness and damping (a's force: a, b and c; b's: a and b; c's: a and c). Returns (each port's inputs, each port's expected list)."""
    motions = {port: [f"{port}.{c}" for c in ("x", "y", "z", "vx", "vy", "vz")] for port in "abc"}
    expected = {"a": motions["a"] + motions["b"] + motions["c"], "b": motions["a"] + motions["b"],
                "c": motions["a"] + motions["c"]}
    listed = listed_dependencies(fmu)
    for port in "abc":
        for c in "xyz":
            assert listed[f"{port}.f{c}"] == expected[port], (port, c, listed[f"{port}.f{c}"])
    return motions, expected


def test_a_motion_ports_force_depends_on_the_motion_ports_its_springs_join_it_to(test_fmu):
    # joined_hooks: motion ports a, b and c on particles n0, n1 and n4 of a line of six; a and b
    # are joined by two springs, a and c by one across the line, b and c by none (n2 and n3, free,
    # lie between them). A port's force is the pull of the springs at its particle (and gravity and
    # mass damping on it): it changes with its own inputs and with those of the motion ports at the
    # springs' other ends, and with no other input, so the ModelStructure lists exactly these (a's
    # force: a, b and c; b's: a and b; c's: a and c), each port's six inputs in ascending order.
    # Listing every motion port for every port's force made the Outputs grow with the square of the
    # motion ports: 2 886 000 indices for 400 of them along a chain, where 13 200 are dependencies.
    fmu = test_fmu("joined_hooks")
    variables = read_model_description(str(fmu)).modelVariables
    motions, expected = check_hooks_dependencies(fmu)
    # At a displaced, moving state (every spring stretched and turning in 3D, so that no derivative
    # vanishes by symmetry), the analytic derivative of each port's force is nonzero for every
    # listed input and exactly zero for every other, and setting an input that is not listed leaves
    # the force as it was, to the bit.
    inst = Instance(fmu).start()
    try:
        s, vr = inst.slave, inst.vr
        moved = {"a": (0.1, 0.2, -0.1, 0.3, -0.2, 0.1), "b": (1.1, -0.1, 0.2, -0.1, 0.2, 0.3),
                 "c": (3.9, 0.3, 0.1, 0.2, 0.1, -0.3)}
        for port, values in moved.items():
            s.setReal([vr[n] for n in motions[port]], list(values))
        s.doStep(0.0, 0.01)
        inputs = [v.name for v in variables if v.causality == "input"]
        for port in "abc":
            forces = [vr[f"{port}.f{c}"] for c in "xyz"]
            before = s.getReal(forces)
            for known in inputs:
                d = s.getDirectionalDerivative(forces, [vr[known]], [1.0])
                if known in expected[port]:
                    assert all(x != 0.0 for x in d), (port, known, d)
                else:
                    assert d == [0.0, 0.0, 0.0], (port, known, d)
                    value = s.getReal([vr[known]])[0]
                    s.setReal([vr[known]], [value + 0.5])
                    assert s.getReal(forces) == before, (port, known)
                    s.setReal([vr[known]], [value])
    finally:
        inst.free()


def test_the_listed_motion_ports_are_in_order_once_whatever_the_springs_order(test_fmu):
    # crossed_hooks: motion ports a, b and c on particles n0, n1 and n2, c the last port, with the
    # springs a-c, a-b and c-a in that order, so that the springs name a's neighbours c, b, c and
    # c's a twice. Each port's force still lists its own inputs and those of the ports a spring
    # joins it to, each port's six once, in ascending order (a's force: a, b and c; b's: a and b;
    # c's: a and c); c, the last port, has the list the table's last offset ends.
    check_hooks_dependencies(test_fmu("crossed_hooks"))


def check_exact_dependencies(fmu, expected, moved, parameter_sets):
    """The ModelStructure lists for each output named in `expected` exactly the inputs given there,
    in ascending order, each once; at the state `moved` (each motion port's x, y, z, vx, vy, vz)
    with each of parameter_sets, setting an input that is not listed leaves the output as it was,
    to the bit, with a directional derivative of exactly 0, and every listed input changes the
    output at once, with a derivative other than 0, for at least one of them. 0.37 m or m/s moves
    each output by far more than its round-off."""
    variables = read_model_description(str(fmu)).modelVariables
    inputs = [v.name for v in variables if v.causality == "input"]
    listed = listed_dependencies(fmu)
    wanted = {name: sorted(set(names), key=inputs.index) for name, names in expected.items()}
    assert {name: listed[name] for name in wanted} == wanted
    real = {name: set() for name in wanted}
    for start_values in parameter_sets:
        inst = Instance(fmu).start(start_values=start_values)
        try:
            s, vr = inst.slave, inst.vr
            for port, values in moved.items():
                s.setReal([vr[f"{port}.{c}"] for c in ("x", "y", "z", "vx", "vy", "vz")], list(values))
            s.doStep(0.0, 0.01)
            for name in wanted:
                for known in inputs:
                    before = s.getReal([vr[name]])[0]
                    d = s.getDirectionalDerivative([vr[name]], [vr[known]], [1.0])[0]
                    value = s.getReal([vr[known]])[0]
                    s.setReal([vr[known]], [value + 0.37])
                    after = s.getReal([vr[name]])[0]
                    s.setReal([vr[known]], [value])
                    if known in wanted[name]:
                        if after != before and d != 0.0:
                            real[name].add(known)
                    else:
                        assert after == before and d == 0.0, (name, known, before, after, d)
        finally:
            inst.free()
    assert real == {name: set(names) for name, names in wanted.items()}


def test_the_energies_list_exactly_the_inputs_they_change_with_at_once(test_fmu):
    # energy_ports: motion ports a (a spring of 40 N/m), b (a damper alone: stiffness 0), c (a
    # load of (2, 0, 0) N, no spring) and d (a spring of stiffness kd and a load (fx, 0, 0)), under
    # gravity (0, gy, -9.81); kd, fx and gy are tunable parameters at 0. The kinetic energy changes
    # at once with every motion port's velocity (masses are > 0); the elastic energy with the
    # position of a port a spring of some stiffness ends at, kd's included (a parameter can make it
    # other than 0), not b's or c's; the gravitational energy with a port's position along the axes
    # its weight or load can have a component (-(m g + F).x: y and z everywhere, x at c and d); the
    # inputs' work with all of these (a motion set elsewhere does the work of the energy it adds at
    # once); the dissipated energy, an integral, with none. Listing every motion port's position
    # for the elastic and gravitational energies (and for the inputs' work) claimed feed-through
    # from b.x to the elastic energy, from a.x to gravity's, and so on, algebraic loops of a master
    # that no physics has.
    position = {p: [f"{p}.{c}" for c in "xyz"] for p in "abcd"}
    velocity = [f"{p}.v{c}" for p in "abcd" for c in "xyz"]
    gravity = ["a.y", "a.z", "b.y", "b.z"] + position["c"] + position["d"]
    elastic = position["a"] + position["d"]
    expected = {"energy.kinetic": velocity, "energy.elastic": elastic, "energy.gravity": gravity,
                "energy.dissipated": [], "energy.input": velocity + elastic + gravity}
    # At the packaged parameters (kd, fx and gy 0) and with them set (the dependencies they open
    # then real), at a state where every port is displaced and moving.
    moved = {"a": (0.1, 0.2, -0.1, 0.3, -0.2, 0.1), "b": (2.1, -0.1, 0.2, -0.1, 0.2, 0.3),
             "c": (3.1, 0.3, 0.1, 0.2, 0.1, -0.3), "d": (3.9, -0.2, 0.3, -0.3, 0.1, 0.2)}
    check_exact_dependencies(test_fmu("energy_ports"), expected, moved, ({}, {"kd": 30.0, "fx": 1.5, "gy": 2.0}))


def force_lists(lists):
    """{port: [inputs of its fx, of its fy, of its fz]} as {"port.fx": inputs, ...}."""
    return {f"{port}.f{c}": names for port, by_component in lists.items() for c, names in zip("xyz", by_component)}


def test_a_motion_ports_force_lists_exactly_the_inputs_it_changes_with_at_once(test_fmu):
    # A motion port's force is m (g - alpha v) + F at its particle plus, for each spring there,
    # [ks (L - l0) + kd (u . dv)] u: a spring's stiffness makes it change with the positions of
    # both ends, its damping with their positions (u turns) and velocities, mass damping with the
    # port's own velocity along the force alone; gravity and the loads are constant. force_ports
    # (alpha, ks and kd tunable parameters at 0): a at a spring of 40 N/m without damping, b at a
    # damper alone (0.3 N s/m), c at a load and no spring, d and e joined by a spring of 30 N/m
    # without damping, e also at a spring of stiffness ks and damping kd, f and g joined by a
    # spring of neither. Listing the six inputs of the port and of every port a spring joins it to
    # claimed that d's force changes with e's velocity, c's with its position, and so on:
    # feed-through that no physics has, which makes a master see algebraic loops (126 inputs
    # listed for the 21 forces, 69 of them real). energy_ports (mass damping the number 0, every
    # spring damped): a, b and d list their six inputs, c, at a load and no spring, none.
    position = {p: [f"{p}.{c}" for c in "xyz"] for p in "abcdefg"}
    velocity = {p: [f"{p}.v{c}" for c in "xyz"] for p in "abcdefg"}

    def own_velocity(port, extra=()):
        return [[*extra, v] for v in velocity[port]]

    expected = {"a": own_velocity("a", position["a"]), "b": [position["b"] + velocity["b"]] * 3,
                "c": own_velocity("c"), "d": own_velocity("d", position["d"] + position["e"]),
                "e": [position["d"] + position["e"] + velocity["e"]] * 3, "f": own_velocity("f"),
                "g": own_velocity("g")}
    # Every port displaced and moving, off the line of the springs, so that no derivative vanishes
    # by symmetry; 0.37 m or m/s moves each force by far more than its round-off.
    moved = {"a": (0.1, 0.2, -0.1, 0.3, -0.2, 0.1), "b": (2.1, -0.1, 0.2, -0.1, 0.2, 0.3),
             "c": (4.1, 0.3, 0.1, 0.2, 0.1, -0.3), "d": (5.1, -0.2, 0.3, -0.3, 0.1, 0.2),
             "e": (5.9, 0.1, -0.2, 0.2, -0.3, 0.1), "f": (8.1, 0.2, 0.1, 0.1, 0.3, -0.2),
             "g": (9.1, -0.3, 0.2, -0.2, 0.1, 0.3)}
    check_exact_dependencies(test_fmu("force_ports"), force_lists(expected), moved,
                             ({}, {"alpha": 0.5, "ks": 25.0, "kd": 0.4}))
    whole = {p: [position[p] + velocity[p]] * 3 for p in "abd"}
    moved = {"a": (0.1, 0.2, -0.1, 0.3, -0.2, 0.1), "b": (2.1, -0.1, 0.2, -0.1, 0.2, 0.3),
             "c": (3.1, 0.3, 0.1, 0.2, 0.1, -0.3), "d": (3.9, -0.2, 0.3, -0.3, 0.1, 0.2)}
    check_exact_dependencies(test_fmu("energy_ports"), force_lists({**whole, "c": [[]] * 3}), moved,
                             ({}, {"kd": 30.0, "fx": 1.5, "gy": 2.0}))


def test_a_motion_ports_force_lists_the_terms_of_every_spring_at_it_together(test_fmu):
    # merged_ports: motion ports a and b joined by three springs, a spring of 40 N/m, a damper of
    # 0.3 N s/m and a spring of strain stiffness 20 N, in that order, each spring with one of the
    # two forces: a's and b's forces change with the positions and velocities of both, the
    # damper's terms merged with the others' whether the port is the springs' first end (a) or
    # their second (b), and whichever spring comes last; c at a spring of strain stiffness E alone
    # and d at a damper of section damping cs alone (E and cs tunable parameters at 0, the forms
    # per strain and per section): c's force changes with its position, d's with its position and
    # velocity; mass damping, the number 0.05 1/s, adds each port's own velocity along the force.
    # Keeping a port's own terms or a neighbour's from the last spring alone, or from the first,
    # left out the damper's velocities; keeping those common to the springs left out everything.
    position = {p: [f"{p}.{c}" for c in "xyz"] for p in "abcd"}
    velocity = {p: [f"{p}.v{c}" for c in "xyz"] for p in "abcd"}
    pair = position["a"] + velocity["a"] + position["b"] + velocity["b"]
    expected = {"a": [pair] * 3, "b": [pair] * 3, "c": [position["c"] + [v] for v in velocity["c"]],
                "d": [position["d"] + velocity["d"]] * 3}
    # Every port displaced and moving, off the line of the springs, so that no derivative vanishes
    # by symmetry; 0.37 m or m/s moves each force by far more than its round-off.
    moved = {"a": (0.1, 0.2, -0.1, 0.3, -0.2, 0.1), "b": (1.1, -0.1, 0.2, -0.1, 0.2, 0.3),
             "c": (3.1, 0.3, 0.1, 0.2, 0.1, -0.3), "d": (6.1, -0.2, 0.3, -0.3, 0.1, 0.2)}
    check_exact_dependencies(test_fmu("merged_ports"), force_lists(expected), moved, ({}, {"E": 25.0, "cs": 40.0}))


def test_every_variable_has_the_unit_of_its_quantity(test_fmu):
    # docs/fmu.md's table of variables: positions in m, velocities in m/s, forces in N, energies in
    # J, the tolerances of positions and velocities in m and m/s, the largest step in s, the
    # relative tolerance 1; Integer and String settings have none. Each unit is defined by its
    # exponents of the SI base units (FMI 2.0, 2.2.2): N = kg m s^-2, J = kg m^2 s^-2.
    md = read_model_description(str(test_fmu("driven_oscillator")))
    quantity = {"x": "m", "y": "m", "z": "m", "vx": "m/s", "vy": "m/s", "vz": "m/s", "fx": "N", "fy": "N", "fz": "N"}
    settings = {"solver.rtol": "1", "solver.atol_position": "m", "solver.atol_velocity": "m/s",
                "solver.max_step": "s"}
    seen = set()
    for v in md.modelVariables:
        head, _, field = v.name.rpartition(".")
        if head in ("base", "tip") or head.startswith("p["):
            expected = quantity[field]
        elif head == "energy":
            expected = "J"
        elif v.name in settings:
            expected = settings[v.name]
        else:
            continue
        assert v.unit == expected, (v.name, v.unit, expected)
        seen.add(v.name)
    assert {"base.vx", "tip.vz", "p[1].vy", "energy.elastic", "solver.atol_velocity"} <= seen
    assert all(v.unit is None for v in md.modelVariables if v.type in ("Integer", "String"))
    base = {u.name: (u.baseUnit.kg, u.baseUnit.m, u.baseUnit.s) for u in md.unitDefinitions}
    assert {name: base[name] for name in ("m", "m/s", "N", "J", "s", "1")} == {
        "m": (0, 1, 0), "m/s": (0, 1, -1), "N": (1, 1, -2), "J": (1, 2, -2), "s": (0, 0, 1), "1": (0, 0, 0)}
