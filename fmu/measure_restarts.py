#!/usr/bin/env python3
"""Measures what re-initialising CVODE at every communication point costs an FMU.

    python fmu/measure_restarts.py MODEL.fmu [--step 1e-3] [--stop 1] [--repeat 5] [--stop-time-defined]

Runs the FMU with small communication steps twice, side by side: as it is (CVODE keeps its
history over communication points) and with a restart forced at every communication point
(fmi2SetFMUstate of the state just saved re-initialises the solver from it). With --stop-time-defined
the master gives fmi2SetupExperiment the stop time, so that CVODE may step past communication
points while the inputs are held (they are here: none is set). Prints, per simulated
second, the internal steps and right-hand-side evaluations (from the logSolver messages) and the
median wall time of several runs, and the ratios.
"""
import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests" / "python"))
from fmu_helpers import Instance  # noqa: E402


def run(fmu, step, stop, restart, stop_time_defined):
    inst = Instance(fmu, "measure", logging_on=True)
    inst.slave.setDebugLogging(True, ["logSolver"])
    inst.start(stop_time=stop if stop_time_defined else None)
    n = int(round(stop / step))
    begin = time.perf_counter()
    for k in range(n):
        if restart:
            state = inst.slave.getFMUstate()
            inst.slave.setFMUstate(state)
            inst.slave.freeFMUstate(state)
        inst.slave.doStep(k * step, step)
    wall = time.perf_counter() - begin
    reports = inst.solver_reports()
    steps, rhs = sum(r.steps for r in reports), sum(r.rhs for r in reports)
    inst.free()
    return steps / stop, rhs / stop, wall / stop


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("fmu")
    parser.add_argument("--step", type=float, default=1e-3)
    parser.add_argument("--stop", type=float, default=1.0)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--stop-time-defined", action="store_true")
    args = parser.parse_args()
    rows = {}
    for restart in (False, True):
        runs = [run(args.fmu, args.step, args.stop, restart, args.stop_time_defined) for _ in range(args.repeat)]
        steps, rhs = runs[0][0], runs[0][1]
        wall = statistics.median(r[2] for r in runs)
        label = "restart every step" if restart else "keep history"
        rows[restart] = (steps, rhs, wall)
        print(f"{label:20s} step={args.step:g} steps_per_s={steps:.0f} rhs_per_s={rhs:.0f} wall_s_per_s={wall:.4f}")
    keep, again = rows[False], rows[True]
    print(f"ratio restart/keep: steps {again[0] / keep[0]:.2f} rhs {again[1] / keep[1]:.2f} wall {again[2] / keep[2]:.2f}")


if __name__ == "__main__":
    main()
