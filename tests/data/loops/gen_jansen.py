#!/usr/bin/env python3
"""Writes tests/data/loops/jansen.yaml: one Jansen leg (Theo Jansen's Strandbeest), mm and deg.

    python3 tests/data/loops/gen_jansen.py > tests/data/loops/jansen.yaml

Jansen's lengths ("holy numbers", mm): a = 38, b = 41.5, c = 39.3, d = 40.1, e = 55.8, f = 39.4,
g = 36.7, h = 65.7, i = 49, j = 50, k = 61.9, l = 7.8, m = 15. Crank O at the origin, fixed pivot
Z = (-a, -l). At crank angle t: M = m (cos t, sin t); J (|MJ| = j, |ZJ| = b, the upper intersection); K (|MK| = k,
|ZK| = c, the lower); E (|ZE| = d, |JE| = e, the left); F (|EF| = f, |KF| = g, the left);
P the foot (|FP| = h, |KP| = i, the lower).
"""
import math

a, b, c, d, e, f, g, h, i, j, k, l, m = 38, 41.5, 39.3, 40.1, 55.8, 39.4, 36.7, 65.7, 49, 50, 61.9, 7.8, 15


def meet(p, rp, q, rq, side):
    """The intersection of circles (p, rp) and (q, rq) left (side=+1) or right (-1) of p->q."""
    dx, dy = q[0] - p[0], q[1] - p[1]
    D = math.hypot(dx, dy)
    x = (rp * rp - rq * rq + D * D) / (2 * D)
    y = math.sqrt(rp * rp - x * x)
    ux, uy = dx / D, dy / D
    return (p[0] + x * ux - side * y * uy, p[1] + x * uy + side * y * ux)


t = 0.0
O, Z = (0.0, 0.0), (-a, -l)
M = (m * math.cos(t), m * math.sin(t))
def pick(p, rp, q, rq, key):
    """Of the two intersections, the one with the smallest key."""
    return min((meet(p, rp, q, rq, s) for s in (+1, -1)), key=key)


J = pick(Z, b, M, j, lambda v: -v[1])  # the upper one
K = pick(Z, c, M, k, lambda v: v[1])   # the lower one
E = pick(Z, d, J, e, lambda v: v[0])   # the left one
F = pick(E, f, K, g, lambda v: v[0])   # the left one
P = pick(F, h, K, i, lambda v: v[1])   # the lower one


def body(name, origin, to, pts, mass):
    """A body frame at `origin` with its x axis toward `to`; points given in world."""
    ang = math.atan2(to[1] - origin[1], to[0] - origin[0])
    cs, sn = math.cos(ang), math.sin(ang)
    loc = {n: ((p[0] - origin[0]) * cs + (p[1] - origin[1]) * sn,
               -(p[0] - origin[0]) * sn + (p[1] - origin[1]) * cs) for n, p in pts.items()}
    cx = sum(v[0] for v in loc.values()) / len(loc)
    cy = sum(v[1] for v in loc.values()) / len(loc)
    ptxt = ", ".join(f"{n}: [{v[0]!r}, {v[1]!r}]" for n, v in loc.items())
    return (f"  - name: {name}\n    mass: {mass}\n    inertia: {mass * 300}\n"
            f"    com: [{cx!r}, {cy!r}]\n"
            f"    pose: [{origin[0]!r}, {origin[1]!r}, {math.degrees(ang)!r}]\n"
            f"    points: {{{ptxt}}}\n")


print(f"""# jansen.yaml - one Jansen leg (Strandbeest), written by tests/data/loops/gen_jansen.py.
# Lengths (mm): a 38, b 41.5, c 39.3, d 40.1, e 55.8, f 39.4, g 36.7, h 65.7, i 49, j 50, k 61.9,
# l 7.8, m 15; design crank angle 0 deg.
# Facts tests rely on: 7 moving bodies, 10 revolutes (three links on the pivots M, Z and K), DOF 1;
# joint-graph loop basis j - b + 1 = 10 - 8 + 1 = 3; four-bar loops (pins): O-M-J-Z (ground,
# crank, j, b), O-M-K-Z (ground, crank, k, c), M-J-Z-K (j, b, c, k) and the knee Z-E-F-K (d, f,
# g, c: upper triangle, link f, foot triangle, link c), which has no ground link.
orthomech: 1
name: jansen-leg
description: "one Jansen leg, Jansen's lengths, crank 15 mm"
units: {{length: mm, angle: deg, mass: kg, time: s, force: N}}
ground:
  points: {{O: [0, 0], Z: [{Z[0]!r}, {Z[1]!r}]}}
bodies:
""" + body("crank", O, M, {"O": O, "M": M}, 0.02)
    + body("link_j", M, J, {"M": M, "J": J}, 0.02)
    + body("link_k", M, K, {"M": M, "K": K}, 0.02)
    + body("upper", Z, J, {"Z": Z, "J": J, "E": E}, 0.04)
    + body("link_c", Z, K, {"Z": Z, "K": K}, 0.02)
    + body("link_f", E, F, {"E": E, "F": F}, 0.02)
    + body("foot", F, K, {"F": F, "K": K, "P": P}, 0.04)
    + """joints:
  - {name: O, type: revolute, connects: [ground.O, crank.O]}
  - {name: Mj, type: revolute, connects: [crank.M, link_j.M]}
  - {name: Mk, type: revolute, connects: [crank.M, link_k.M]}
  - {name: J, type: revolute, connects: [link_j.J, upper.J]}
  - {name: Zb, type: revolute, connects: [ground.Z, upper.Z]}
  - {name: Zc, type: revolute, connects: [ground.Z, link_c.Z]}
  - {name: Kk, type: revolute, connects: [link_k.K, link_c.K]}
  - {name: Kf, type: revolute, connects: [link_c.K, foot.K]}
  - {name: E, type: revolute, connects: [upper.E, link_f.E]}
  - {name: F, type: revolute, connects: [link_f.F, foot.F]}
loads:
  - {name: weight, type: gravity, g: [0, -9810]}
measures:
  - {name: crank_angle, type: joint, joint: O}
  - {name: foot_x, type: point, point: foot.P, component: x}
  - {name: foot_y, type: point, point: foot.P, component: y}
drivers:
  - {name: motor, joint: O, speed: 60 rpm}
design_positions:
  - {name: p0, inputs: {O: 0}}
analysis: {driver: motor, steps: 360}""")
