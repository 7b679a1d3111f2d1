#!/usr/bin/env python3
"""Peak drive torque of the crank-rocker against its crank length (orthomech from Python).

Notebook-style: each step is a cell. The crank length is changed as `--set` changes it on the
command line (the `set=` keyword); every variant runs one cycle; matplotlib draws the peak drive
against the length (Agg: a PNG, no display needed).

    python3 examples/python/sweep_link_length.py [--out sweep.png] [--points 11] [--steps 90]
"""

import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

root = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
try:
    import orthomech
except ImportError:  # run in the repository without PYTHONPATH: the package at its top
    sys.path.insert(0, root)
    import orthomech

# %% The mechanism and the sweep
parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--file", default=os.path.join(root, "mechanisms", "crank-rocker.yaml"))
parser.add_argument("--out", default="sweep_link_length.png")
parser.add_argument("--points", type=int, default=11, help="crank lengths in the sweep")
parser.add_argument("--steps", type=int, default=90, help="positions per cycle")
args = parser.parse_args()

mechanism = orthomech.load(args.file)  # read and checked once; errors name file:line:column
nominal = orthomech.info(mechanism)
print(f"{nominal['mechanism']}: {nominal['dof']} DOF, {len(nominal['bodies'])} bodies")

# %% One cycle per crank length (mm, the file's units): the crank's joint point A moves
lengths = np.linspace(24.0, 36.0, args.points)
peaks, unit = [], None
for a in lengths:
    r = orthomech.cycle(
        mechanism,
        steps=args.steps,
        quiet=True,  # the start position moves with the length: no warnings about it
        set={"bodies.crank.points.A": f"[{a!r}, 0]", "bodies.crank.com": f"[{a / 2!r}, 0]"},
    )
    drive = r["peaks"]["drive"]
    peaks.append(drive["peak"])
    unit = drive["unit"]
    print(f"crank {a:6.2f} mm: peak drive {drive['peak']:.6g} {unit}")

# %% The plot
fig, ax = plt.subplots(figsize=(6, 4))
ax.plot(lengths, peaks, "o-")
ax.set_xlabel("crank length [mm]")
ax.set_ylabel(f"peak drive torque [{unit}]")
ax.set_title(f"{nominal['mechanism']}: peak drive over one cycle")
ax.grid(True)
fig.tight_layout()
fig.savefig(args.out, dpi=100)
print(f"wrote {args.out}")
