#!/usr/bin/env python3
"""Writes tests/data/units/press.yaml: an offset slider-crank press (mm, deg) whose process force is
a table keyed on the crank angle over [0 deg, 360 deg] (it wraps with the turn).

    python3 tests/data/units/gen_press.py [design crank angle, deg] > tests/data/units/press.yaml

Geometry: crank r = 40 mm about O = (0, 0); rod l = 160 mm; the ram's pin B slides on the line
y = e = 10 mm. At crank angle t: A = r (cos t, sin t), B = (r cos t + sqrt(l^2 - (e - r sin t)^2), e).
"""
import math
import sys

r, l, e = 40.0, 160.0, 10.0
t = float(sys.argv[1]) if len(sys.argv) > 1 else 0.0
th = math.radians(t)
ax, ay = r * math.cos(th), r * math.sin(th)
bx = ax + math.sqrt(l * l - (e - ay) ** 2)
rod = math.degrees(math.atan2(e - ay, bx - ax))
print(f"""# press.yaml - offset slider-crank press for the units and table-wrap tests (issue 11).
# Written by tests/data/units/gen_press.py {t:g}; the SI twin press-si.yaml by gen_si_twin.py.
# Crank r = 40 mm about O, rod l = 160 mm, ram pin B on the line y = e = 10 mm (offset).
# Facts tests rely on: DOF 1; the process force (5000 N toward the crank) acts for crank angles
# 150...220 deg of every turn (table over crank_angle in [0, 360] deg, wrapping with the turn);
# pressure angle max asin((r + e)/l) = 18.209969 deg at crank 270 deg; ram stroke
# sqrt((l+r)^2 - e^2) - sqrt((l-r)^2 - e^2).
orthomech: 1
name: press
description: "offset slider-crank press r = 40, l = 160, e = 10 mm, process force vs crank angle"
units: {{length: mm, angle: deg, mass: kg, time: s, force: N}}
ground:
  points: {{O: [0, 0], X: [0, {e:g}]}}
bodies:
  - name: crank
    mass: 0.5
    inertia: 300
    com: [20, 0]
    pose: [0, 0, {t!r}]
    points: {{O: [0, 0], A: [40, 0]}}
  - name: rod
    mass: 0.8
    inertia: 1800
    com: [80, 0]
    pose: [{ax!r}, {ay!r}, {rod!r}]
    points: {{A: [0, 0], B: [160, 0]}}
  - name: ram
    mass: 2.0
    inertia: 500
    com: [0, 0]
    pose: [{bx!r}, {e!r}, 0]
    points: {{B: [0, 0]}}
joints:
  - {{name: O, type: revolute, connects: [ground.O, crank.O]}}
  - {{name: A, type: revolute, connects: [crank.A, rod.A]}}
  - {{name: B, type: revolute, connects: [rod.B, ram.B]}}
  - {{name: slide, type: prismatic, connects: [ground.X, ram.B], axis: [1, 0]}}
loads:
  - {{name: weight, type: gravity, g: [0, -9810]}}   # mm/s^2
  - name: process
    type: force
    point: ram.B
    force: [-5000, 0]
    table: {{measure: crank_angle, points: [[0, 0], [150, 0], [170, 1], [200, 1], [220, 0], [360, 0]]}}
measures:
  - {{name: crank_angle, type: joint, joint: O}}
  - {{name: ram_x, type: joint, joint: slide}}
drivers:
  - {{name: motor, joint: O, speed: 60 rpm}}
analysis: {{driver: motor, steps: 360}}""")
