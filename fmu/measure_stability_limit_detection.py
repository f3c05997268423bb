#!/usr/bin/env python3
"""Measures what BDF's stability limit detection changes in an FMU run by a co-simulation master.

    python fmu/measure_stability_limit_detection.py MODEL.fmu [--stop 2] [--step 1e-3]
        [--input NAME --amplitude A [--derivatives]] [--stop-time-defined] [--restore-at T]
    python fmu/measure_stability_limit_detection.py MODEL.fmu --stop 100 --first-step S [S ...] [--restore]

Runs the same master three times: with solver.stability_limit_detection true, with it false, and
as a reference at solver.rtol 1e-10, solver.atol_position 1e-12 and solver.atol_velocity 1e-10.
The master steps from 0 to --stop in communication steps of --step, or in two, to S and on to the
stop, for each S of --first-step. With --input it sets the input NAME to A sin(2 pi t) at every
communication point t (a motion port's NAME.x: NAME.vx with it, A 2 pi cos(2 pi t)), and with
--derivatives gives that input's first derivative too (fmi2SetRealInputDerivatives); else the
inputs are held. --stop-time-defined gives fmi2SetupExperiment the stop time (CVODE then steps
past communication points while the inputs are held). --restore-at T (or --restore: at S) saves
the FMU state at that communication point and restores it at once (CVODE restarts from it).
Prints the internal steps and restarts of each run (from the logSolver messages), the largest
deviation of its position outputs from the reference's at the communication points, whether the
runs with and without detection gave the same outputs to the bit, and for several S the medians.
"""
import argparse
import math
import statistics
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests" / "python"))
from fmu_helpers import Instance  # noqa: E402

TIGHT = {"solver.rtol": 1e-10, "solver.atol_position": 1e-12, "solver.atol_velocity": 1e-10}


def run(fmu, points, args, settings, restore_at):
    """Steps the FMU through the communication points; returns internal steps, restarts and the
    position outputs at every point."""
    inst = Instance(fmu, "measure", logging_on=True)
    try:
        s = inst.slave
        s.setupExperiment(startTime=0.0, stopTime=points[-1] if args.stop_time_defined else None)
        s.enterInitializationMode()
        for name, value in settings.items():
            inst.set(name, value)
        s.exitInitializationMode()
        s.setDebugLogging(True, ["logSolver"])
        names = [v.name for v in inst.md.modelVariables
                 if v.causality == "output" and v.name.rsplit(".", 1)[-1] in ("x", "y", "z")]
        outputs, t, w = [], 0.0, 2.0 * math.pi
        for end in points:
            if args.input:
                a = args.amplitude
                if args.input.endswith(".x"):
                    velocity = args.input[:-2] + ".vx"
                    inst.set(args.input, a * math.sin(w * t))
                    inst.set(velocity, a * w * math.cos(w * t))
                    derivative = (velocity, -a * w * w * math.sin(w * t))
                else:
                    inst.set(args.input, a * math.sin(w * t))
                    derivative = (args.input, a * w * math.cos(w * t))
                if args.derivatives:
                    s.setRealInputDerivatives([inst.vr[derivative[0]]], [1], [derivative[1]])
            if restore_at is not None and abs(t - restore_at) <= 1e-9 * max(1.0, abs(t)):
                state = s.getFMUstate()
                s.setFMUstate(state)
                s.freeFMUstate(state)
            s.doStep(t, end - t)
            outputs.append(inst.get(*names) if len(names) > 1 else [inst.get(*names)])
            t = end
        reports = inst.solver_reports()
        steps, restarts = sum(r.steps for r in reports), sum(r.restarts for r in reports)
        return steps, restarts, np.array(outputs)
    finally:
        inst.free()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("fmu")
    parser.add_argument("--stop", type=float, default=2.0)
    parser.add_argument("--step", type=float, default=1e-3)
    parser.add_argument("--first-step", type=float, nargs="+")
    parser.add_argument("--input")
    parser.add_argument("--amplitude", type=float, default=1.0)
    parser.add_argument("--derivatives", action="store_true")
    parser.add_argument("--stop-time-defined", action="store_true")
    parser.add_argument("--restore-at", type=float)
    parser.add_argument("--restore", action="store_true")
    args = parser.parse_args()
    if args.first_step:
        cases = [([s, args.stop], s if args.restore else None, f"first step {s:g} s") for s in args.first_step]
    else:
        n = int(round(args.stop / args.step))
        points = [(k + 1) * args.step for k in range(n)]
        cases = [(points, args.restore_at, f"step {args.step:g} s")]
    totals = []
    for points, restore_at, label in cases:
        reference = run(args.fmu, points, args, TIGHT, restore_at)[2]
        row = {}
        for detection in (True, False):
            steps, restarts, outputs = run(args.fmu, points, args,
                                           {"solver.stability_limit_detection": detection}, restore_at)
            row[detection] = (steps, restarts, outputs, float(np.max(np.abs(outputs - reference))))
        on, off = row[True], row[False]
        same = np.array_equal(on[2], off[2])
        print(f"{label}: detection on {on[0]} steps, {on[1]} restarts, {on[3]:.2g} m off the reference; "
              f"off {off[0]} steps, {off[1]} restarts, {off[3]:.2g} m; same bits: {'yes' if same else 'no'}",
              flush=True)
        totals.append((on[0], off[0]))
    if len(totals) > 1:
        fewer = sum(1 for a, b in totals if a < b)
        print(f"median steps: detection on {statistics.median(a for a, _ in totals):g}, "
              f"off {statistics.median(b for _, b in totals):g}; on takes fewer in {fewer} of {len(totals)}")


if __name__ == "__main__":
    main()
