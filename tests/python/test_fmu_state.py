"""FMU state: get/set round trips, serialisation into another process, reset, threads."""
import json
import pathlib
import subprocess
import sys
import threading

import numpy as np

from fmu_helpers import Instance

HERE = pathlib.Path(__file__).resolve().parent
OUTPUTS = ["tip.x", "tip.vx", "base.fx", "energy.kinetic", "energy.elastic", "energy.dissipated"]


def run(inst, t0, steps, h=0.01, force=None):
    """Steps from t0; returns the outputs after each step (a forcing signal may be applied)."""
    rows = []
    for n in range(steps):
        t = t0 + n * h
        if force is not None:
            inst.set("tip.fx", force(t))
        inst.slave.doStep(t, h)
        rows.append(inst.get(*OUTPUTS))
    return np.array(rows)


def force(t):
    return 0.5 * np.sin(7.0 * t)


def test_get_set_state_round_trip_continues_identically(test_fmu):
    inst = Instance(test_fmu("driven_oscillator")).start({"d": 0.3})
    try:
        run(inst, 0.0, 30, force=force)
        state = inst.slave.getFMUstate()
        first = run(inst, 0.3, 40, force=force)
        inst.slave.setFMUstate(state)
        second = run(inst, 0.3, 40, force=force)
        # Bit for bit: both continuations start from the same re-initialised solver.
        assert np.array_equal(first, second)
        inst.slave.freeFMUstate(state)
    finally:
        inst.free()


def test_serialised_state_continues_identically_in_a_new_process(test_fmu, tmp_path):
    fmu = test_fmu("driven_oscillator")
    inst = Instance(fmu).start({"d": 0.3, "k": 60.0})
    try:
        run(inst, 0.0, 25, force=force)
        state = inst.slave.getFMUstate()
        blob = inst.slave.serializeFMUstate(state)
        here = run(inst, 0.25, 30, force=force)
        inst.slave.freeFMUstate(state)
    finally:
        inst.free()
    (tmp_path / "state.bin").write_bytes(blob)
    script = f"""
import json, sys
import numpy as np
sys.path.insert(0, {str(HERE)!r})
from fmu_helpers import Instance
from test_fmu_state import run, force
inst = Instance({str(fmu)!r}).start()
state = inst.slave.deSerializeFMUstate(open({str(tmp_path / 'state.bin')!r}, 'rb').read())
inst.slave.setFMUstate(state)
assert inst.get('k') == 60.0 and inst.get('d') == 0.3
print(json.dumps(run(inst, 0.25, 30, force=force).tolist()))
inst.free()
"""
    out = subprocess.run([sys.executable, "-c", script], check=True, capture_output=True, text=True)
    there = np.array(json.loads(out.stdout.strip().splitlines()[-1]))
    assert np.array_equal(here, there)


def test_state_of_another_model_is_refused(test_fmu):
    a = Instance(test_fmu("driven_oscillator")).start()
    b = Instance(test_fmu("hanging")).start()
    try:
        blob = a.slave.serializeFMUstate(a.slave.getFMUstate())
        try:
            b.slave.deSerializeFMUstate(blob)
            raise AssertionError("a state of another model was accepted")
        except Exception:
            pass
        assert "belongs to another model" in b.log_text()
    finally:
        a.free()
        b.free()


def test_instances_in_threads_match_a_lone_instance(test_fmu):
    # Eight instances of two different FMUs stepping in parallel threads each give exactly the
    # results of the same FMU run alone: no state is shared between instances.
    oscillator, hanging = test_fmu("driven_oscillator"), test_fmu("hanging")

    # fmpy changes the process's working directory while it loads an FMU's binary, and an
    # instance's free removes its unpacked folder: both are serialised; setting up, stepping and
    # reading the instances run in parallel.
    loader = threading.Lock()

    def simulate(fmu, name, k, results):
        with loader:
            inst = Instance(fmu, name)
        try:
            inst.start({"k": k})
            names = ["tip.x", "energy.elastic"] if "oscillator" in str(fmu) else ["bob.z", "hook.fz"]
            rows = []
            for n in range(100):
                inst.slave.doStep(n * 0.01, 0.01)
                rows.append(inst.get(*names))
            results[name] = np.array(rows)
        finally:
            with loader:
                inst.free()

    cases = [(oscillator if i % 2 == 0 else hanging, f"i{i}", 40.0 + 10 * i) for i in range(8)]
    alone = {}
    for fmu, name, k in cases:
        simulate(fmu, name, k, alone)
    together = {}
    threads = [threading.Thread(target=simulate, args=(fmu, name, k, together)) for fmu, name, k in cases]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for _, name, _ in cases:
        assert np.array_equal(alone[name], together[name]), name
