#!/usr/bin/env python3
"""Simulates a springmass FMU in fmpy and writes a PNG plot of its outputs.

    python tools/fmu_demo.py MODEL.fmu PLOT.png [--stop-time T] [--step DT]

The FMU's default experiment (stop time and communication step from the model file's
"simulation" settings) is used unless given. One panel per port (positions, velocities and
forces) and one with the energies.
"""
import argparse
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from fmpy import read_model_description, simulate_fmu  # noqa: E402


def positive_seconds(text):
    """A time in seconds for --stop-time and --step: a finite number above zero."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value) or value <= 0.0:
        raise argparse.ArgumentTypeError(f"{text} is not a finite time above 0 s")
    return value


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("fmu")
    parser.add_argument("png")
    parser.add_argument("--stop-time", type=positive_seconds, default=None)
    parser.add_argument("--step", type=positive_seconds, default=None)
    args = parser.parse_args(argv)

    md = read_model_description(args.fmu)
    experiment = md.defaultExperiment
    stop = args.stop_time if args.stop_time is not None else (float(experiment.stopTime) if experiment and experiment.stopTime else 1.0)
    step = args.step if args.step is not None else (float(experiment.stepSize) if experiment and experiment.stepSize else stop / 500)
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    result = simulate_fmu(args.fmu, stop_time=stop, output_interval=step, output=outputs)

    # Group the outputs: "<port>.<quantity>" per port, "energy.<kind>" together.
    groups = {}
    for name in outputs:
        head = name.rsplit(".", 1)[0]
        groups.setdefault(head, []).append(name)
    fig, axes = plt.subplots(len(groups), 1, figsize=(8, 2.6 * len(groups)), sharex=True, squeeze=False)
    units = {v.name: v.unit or (v.declaredType.unit if v.declaredType else "") for v in md.modelVariables}
    for ax, (head, names) in zip(axes[:, 0], groups.items()):
        for name in names:
            ax.plot(result["time"], result[name], label=f"{name} [{units.get(name) or '-'}]")
        ax.set_title(head)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize="small", ncol=3)
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle(f"{md.modelName}: FMU simulated in fmpy ({stop:g} s, step {step:g} s)")
    fig.tight_layout()
    fig.savefig(args.png, dpi=110)
    print(f"fmu_demo: {len(result)} points of {len(outputs)} outputs plotted in {args.png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
