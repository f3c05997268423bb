#!/usr/bin/env python3
"""Runs the split chain's SSP archive in the Open Simulation Platform's libcosim (libcosimpy).

    .venv/bin/python examples/coupled_chain/run_libcosim.py coupled_chain.ssp [--step 0.001] [--stop 2]

libcosim reads the connections and the parameter bindings from SystemStructure.ssd, steps both
FMUs with a fixed communication step and passes the connected values between steps. Prints the
masses' positions at the stop time [m].
"""
import argparse

from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
from libcosimpy.CosimObserver import CosimObserver


def simulate(ssp, step, stop):
    """Positions of m1 and m2 at the stop time [m], communication step `step` [s]."""
    log_output_level(CosimLogLevel.WARNING)
    execution = CosimExecution.from_ssp_file(ssp_path=str(ssp), step_size=int(round(step * 1e9)))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer=observer)
    if not execution.simulate_until(target_time=int(round(stop * 1e9))):
        raise RuntimeError(f"libcosim stopped: {execution.status()}")
    positions = {}
    for instance, variable in (("left", "m1.x"), ("right", "m2.x")):
        index = execution.slave_index_from_instance_name(instance)
        reference = {v.name.decode(): v.reference for v in execution.slave_variables(slave_index=index)}[variable]
        positions[variable] = observer.last_real_values(slave_index=index, variable_references=[reference])[0]
    return positions


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("ssp", help="the archive make_ssp.sh wrote")
    parser.add_argument("--step", type=float, default=1e-3, help="communication step [s] (default 0.001)")
    parser.add_argument("--stop", type=float, default=2.0, help="stop time [s] (default 2)")
    args = parser.parse_args()
    for name, x in simulate(args.ssp, args.step, args.stop).items():
        print(f"{name} = {x:.9f} m at t = {args.stop:g} s")


if __name__ == "__main__":
    main()
