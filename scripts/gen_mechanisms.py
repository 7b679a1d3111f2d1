#!/usr/bin/env python3
"""Generate the bundled mechanism files in mechanisms/ (python3 standard library only).

    python3 scripts/gen_mechanisms.py            # write every file, then check them
    python3 scripts/gen_mechanisms.py --check    # only check the files on disk

Every design pose is computed here in closed form (circle intersections, the published Andrews
angles) and printed at full double precision (repr), so that every joint holds at the design
position to ~1e-13 in file units. The numbers quoted in the comment block of each file (Grashof
sums, dead points, limit positions, time ratio, energies) are computed here too, so they cannot
drift from the geometry.

The check re-reads each written file (with PyYAML when it is installed, which is only a test
convenience: the generator itself needs nothing outside the standard library), evaluates every
joint equation at the design poses, counts Grübler's n − n_c and computes the rank of the
constraint Jacobian by finite differences and Gaussian elimination, and prints one line per file.
"""
import math
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "mechanisms")


# ---------------------------------------------------------------------------------------------
# small plane geometry
def u(t):
    return (math.cos(t), math.sin(t))


def add(p, q):
    return (p[0] + q[0], p[1] + q[1])


def sub(p, q):
    return (p[0] - q[0], p[1] - q[1])


def mul(s, p):
    return (s * p[0], s * p[1])


def rot(t, s):
    c, si = math.cos(t), math.sin(t)
    return (c * s[0] - si * s[1], si * s[0] + c * s[1])


def norm(p):
    return math.hypot(p[0], p[1])


def ang(p):
    return math.atan2(p[1], p[0])


def dot(p, q):
    return p[0] * q[0] + p[1] * q[1]


def circle_cut(P, rp, Q, rq, side):
    """Point X with |X − P| = rp, |X − Q| = rq; side = +1: X left of the direction P→Q."""
    d = norm(sub(Q, P))
    e = mul(1.0 / d, sub(Q, P))
    along = (rp * rp - rq * rq + d * d) / (2.0 * d)
    h2 = rp * rp - along * along
    if h2 < 0.0:
        raise ValueError("circles do not intersect")
    h = math.sqrt(h2)
    return add(add(P, mul(along, e)), mul(side * h, (-e[1], e[0])))


def deg(x):
    return math.degrees(x)


def wrap180(a):
    a = math.fmod(a + 180.0, 360.0)
    if a < 0:
        a += 360.0
    return a - 180.0


def wrap360(a):
    a = math.fmod(a, 360.0)
    return a + 360.0 if a < 0 else a


def interior_angle_deg(p, q):
    """Angle between two vectors, 0..180°."""
    c = dot(p, q) / (norm(p) * norm(q))
    return deg(math.acos(max(-1.0, min(1.0, c))))


# ---------------------------------------------------------------------------------------------
# YAML text helpers
def num(x):
    """Shortest exact text of a number: integers as integers, floats by repr (round trip)."""
    if isinstance(x, str):
        return x
    if isinstance(x, int):
        return str(x)
    x = float(x)
    if x == 0.0:
        return "0"
    if x == int(x) and abs(x) < 1e15:
        return str(int(x))
    return repr(x)


def vec(v):
    return "[" + ", ".join(num(x) for x in v) + "]"


def pts(d):
    return "{" + ", ".join(f"{k}: {vec(v)}" for k, v in d.items()) + "}"


def table(points):
    return "[" + ", ".join(vec(p) for p in points) + "]"


def body_block(name, mass, pose, points, inertia=None, com=None, particle=False, outline=None,
               notes=None):
    lines = [f"  - name: {name}"]
    if notes:
        for n in notes:
            lines.append(f"    # {n}")
    if particle:
        lines.append("    type: particle")
    lines.append(f"    mass: {num(mass)}")
    if inertia is not None:
        lines.append(f"    inertia: {num(inertia)}")
    if com is not None:
        lines.append(f"    com: {vec(com)}")
    lines.append(f"    pose: {vec(pose)}")
    if points:
        lines.append(f"    points: {pts(points)}")
    if outline:
        lines.append(f"    outline: {table(outline)}")
    return lines


def header(text):
    out = []
    for line in text.strip("\n").split("\n"):
        out.append(("# " + line).rstrip())
    return out


def write(fname, lines):
    path = os.path.join(OUT, fname)
    with open(path, "w", encoding="utf-8") as f:
        f.write("\n".join(lines) + "\n")
    return path


# design input angles are printed as the exact degree values they were chosen as
DEG_IN = {}


def rad_in(degrees):
    r = math.radians(degrees)
    DEG_IN[r] = degrees
    return r


def rod_inertia(m, L):
    """Uniform slender rod about its centre: m L^2 / 12 (15 significant digits)."""
    return float(f"{m * L * L / 12.0:.15g}")


def plate_inertia(m, pts3):
    """Thin uniform triangular plate about its centroid: m (a² + b² + c²) / 36."""
    a = norm(sub(pts3[0], pts3[1]))
    b = norm(sub(pts3[1], pts3[2]))
    c = norm(sub(pts3[2], pts3[0]))
    return float(f"{m * (a * a + b * b + c * c) / 36.0:.15g}")


def centroid(pts3):
    return ((pts3[0][0] + pts3[1][0] + pts3[2][0]) / 3.0, (pts3[0][1] + pts3[1][1] + pts3[2][1]) / 3.0)


MM = "units: {length: mm, angle: deg, mass: kg, time: s, force: N}"
SI = "units: {length: m, angle: rad, mass: kg, time: s, force: N}"
G_MM = "  - {name: weight, type: gravity, g: [0, -9810]}"
G_SI = "  - {name: weight, type: gravity, g: [0, -9.81]}"


# ---------------------------------------------------------------------------------------------
# four-bar data shared by the crank-rocker and the six-bars
def fourbar(a, b, c, d, th2, side=+1, A0=(0.0, 0.0)):
    B0 = (A0[0] + d, A0[1])
    A = add(A0, mul(a, u(th2)))
    B = circle_cut(A, b, B0, c, side)
    return A, B, ang(sub(B, A)), ang(sub(B, B0))


def grashof(lengths):
    s, l = min(lengths), max(lengths)
    rest = sorted(lengths)[1:3]
    return s, l, rest[0], rest[1]


def limit_positions(a, b, c, d, side):
    """Crank angles (deg, 0..360) where crank and coupler are collinear, with the rocker angle:
    extended (|A0B| = a + b) and folded (|A0B| = b − a)."""
    A0, B0 = (0.0, 0.0), (d, 0.0)
    res = {}
    for kind, R in (("extended", a + b), ("folded", b - a)):
        # B on circle R about A0 and c about B0, on the branch of the design (left of A0→B0 when
        # side = +1 for the points above the ground line)
        B = circle_cut(A0, R, B0, c, side)
        th2 = ang(B) if kind == "extended" else ang(B) + math.pi
        res[kind] = (wrap360(deg(th2)), deg(ang(sub(B, B0))), B)
    return res


# ---------------------------------------------------------------------------------------------
# 1. crank-rocker
def gen_crank_rocker():
    a, b, c, d = 30.0, 80.0, 60.0, 70.0
    s, l, p, q = grashof([a, b, c, d])
    th2 = rad_in(60)
    A, B, th3, th4 = fourbar(a, b, c, d, th2)
    Pl = (40.0, 20.0)  # coupler point, coupler frame
    P = add(A, rot(th3, Pl))
    lim = limit_positions(a, b, c, d, +1)
    ext, fold = lim["extended"], lim["folded"]
    swing = abs(ext[1] - fold[1])
    # crank angle from folded to extended (ccw) and back
    fwd = wrap360(ext[0] - fold[0])
    qrr = fwd / (360.0 - fwd) if fwd > 180 else (360.0 - fwd) / fwd
    # transmission angle extremes (coupler–rocker) at crank angles 0 and 180
    mu0 = deg(math.acos((b * b + c * c - (d - a) ** 2) / (2 * b * c)))
    mu180 = deg(math.acos((b * b + c * c - (d + a) ** 2) / (2 * b * c)))
    # design positions for `validate`: coupler point at three crank angles on the same circuit
    dps = []
    for name, t in (("p1", 60.0), ("p2", 150.0), ("p3", 270.0)):
        Ai, Bi, t3, t4 = fourbar(a, b, c, d, math.radians(t))
        Pi = add(Ai, rot(t3, Pl))
        dps.append((name, t, Pi, deg(t3)))
    m = {"crank": 0.03, "coupler": 0.08, "rocker": 0.06}
    txt = f"""
crank-rocker.yaml — Grashof crank-rocker four-bar, driven by its crank at 300 rpm.
The reference example of docs/file-format.md: every section of the format is used once.

Source: chosen for this project (a textbook-proportioned crank-rocker).
  Links (mm): ground A0B0 d = {num(d)}, crank A0A a = {num(a)}, coupler AB b = {num(b)}, rocker B0B c = {num(c)}.
  Grashof: s + l = {num(s)} + {num(l)} = {num(s + l)} <= p + q = {num(p)} + {num(q)} = {num(p + q)}; the shortest link (the
  crank) is adjacent to the ground -> crank-rocker (the crank turns fully, the rocker oscillates).
  Masses: 1 g per mm of link length (about a 20 x 6 mm steel bar, 0.94 g/mm), uniform slender
  rods: com at mid-length, inertia m L^2/12 (kg mm^2). Coupler point P = [{num(Pl[0])}, {num(Pl[1])}] in the
  coupler frame (the coupler is drawn as the triangle A-P-B; its mass is still that of the rod AB).
Frames: each link's local x axis runs from its first joint to its second (crank A0->A,
  coupler A->B, rocker B0->B); joint `A0` measures the crank angle, joint `B0` the rocker angle.
Design pose: crank angle 60 deg, open assembly (B above the ground line A0B0), every joint closed
  to ~1e-13 mm (computed by scripts/gen_mechanisms.py).

Facts tests rely on:
  - 3 moving bodies, 4 revolutes: n = 9, n_c = 8, Grubler 1, rank 8, DOF 1 everywhere on the cycle
    (a Grashof crank-rocker has no change point); no redundant equation.
  - Rocker limit (extreme) positions, where crank and coupler are collinear (dead points when the
    linkage is driven from the rocker; the crank passes them freely):
      extended (|A0B| = a + b = {num(a + b)}): crank {ext[0]:.6f} deg, rocker {ext[1]:.6f} deg
      folded   (|A0B| = b - a = {num(b - a)}): crank {fold[0]:.6f} deg, rocker {fold[1]:.6f} deg
    rocker swing {swing:.6f} deg; crank turns {fwd:.6f} deg from folded to extended (ccw) and
    {360 - fwd:.6f} deg back: time ratio {qrr:.6f}.
  - Transmission angle (coupler-rocker) extremes: {mu0:.6f} deg at crank 0 deg, {mu180:.6f} deg at crank 180 deg.
  - Driven from the crank there is no dead point: d^T F never vanishes.
  - Measures: crank_angle, rocker_angle (joint angles, deg), coupler_angle (body angle),
    transmission (coupler-rocker angle, bodies [coupler, rocker]), P_x, P_y (coupler point, mm),
    P_vx, P_vy (mm/s), P_ax (mm/s^2).
  - Design positions p1..p3 are exact coupler-point positions of the open circuit at crank
    60, 150, 270 deg (rounded to 1e-6 mm), in driving order: `validate` must pass all three.
"""
    lines = header(txt)
    lines += [
        "orthomech: 1",
        "name: crank-rocker",
        'description: "Grashof crank-rocker four-bar (30/80/60 mm on a 70 mm ground), crank at 300 rpm"',
        MM,
        "ground:",
        f"  points: {pts({'A0': (0, 0), 'B0': (d, 0)})}",
        "bodies:",
    ]
    lines += body_block("crank", m["crank"], (0, 0, DEG_IN[th2]), {"A0": (0, 0), "A": (a, 0)},
                        rod_inertia(m["crank"], a), (a / 2, 0))
    lines += body_block("coupler", m["coupler"], (A[0], A[1], deg(th3)),
                        {"A": (0, 0), "B": (b, 0), "P": Pl}, rod_inertia(m["coupler"], b), (b / 2, 0),
                        outline=[(0, 0), Pl, (b, 0), (0, 0)])
    lines += body_block("rocker", m["rocker"], (d, 0, deg(th4)), {"B0": (0, 0), "B": (c, 0)},
                        rod_inertia(m["rocker"], c), (c / 2, 0))
    lines += [
        "joints:",
        "  - {name: A0, type: revolute, connects: [ground.A0, crank.A0]}",
        "  - {name: A, type: revolute, connects: [crank.A, coupler.A]}",
        "  - {name: B, type: revolute, connects: [coupler.B, rocker.B]}",
        "  - {name: B0, type: revolute, connects: [ground.B0, rocker.B0]}",
        "loads:",
        G_MM + "   # mm/s^2",
        "measures:",
        "  - {name: crank_angle, type: joint, joint: A0}",
        "  - {name: rocker_angle, type: joint, joint: B0}",
        "  - {name: coupler_angle, type: angle, body: coupler}",
        "  - {name: transmission, type: angle, bodies: [coupler, rocker]}",
        "  - {name: P_x, type: point, point: coupler.P, component: x}",
        "  - {name: P_y, type: point, point: coupler.P, component: y}",
        "  - {name: P_vx, type: point, point: coupler.P, component: x, derivative: 1}",
        "  - {name: P_vy, type: point, point: coupler.P, component: y, derivative: 1}",
        "  - {name: P_ax, type: point, point: coupler.P, component: x, derivative: 2}",
        "drivers:",
        "  - {name: motor, joint: A0, speed: 300 rpm}",
        "design_positions:",
    ]
    for name, t, Pi, t3 in dps:
        lines.append(f"  - name: {name}")
        lines.append(f"    inputs: {{A0: {num(t)}}}")
        if name == "p1":
            lines.append(f"    target: {{point: coupler.P, at: [{Pi[0]:.6f}, {Pi[1]:.6f}], "
                         f"angle: {t3:.6f}, tolerance: 0.5}}")
        else:
            lines.append(f"    target: {{point: coupler.P, at: [{Pi[0]:.6f}, {Pi[1]:.6f}], tolerance: 0.5}}")
    lines += ["analysis: {driver: motor, steps: 360}"]
    write("crank-rocker.yaml", lines)
    return dict(ext=ext, fold=fold, swing=swing, qrr=qrr, mu=(mu0, mu180))


# ---------------------------------------------------------------------------------------------
# 2. double-rocker (non-Grashof triple rocker)
def gen_double_rocker():
    d, a, b, c = 100.0, 60.0, 40.0, 65.0
    s, l, p, q = grashof([a, b, c, d])
    # input limits: coupler and output collinear, |B0A| = b + c (|c − b| = 25 is unreachable: a + 25 < d)
    cos_lim = (a * a + d * d - (b + c) ** 2) / (2 * a * d)
    th_lim = deg(math.acos(cos_lim))
    assert a + abs(c - b) < d
    # output limits: input and coupler collinear, |A0B| = a + b (a − b = 20: 20 + c < d unreachable)
    cos_o = (d * d + c * c - (a + b) ** 2) / (2 * d * c)
    th_o = 180.0 - deg(math.acos(cos_o))
    assert (a - b) + c < d
    th2 = rad_in(0)
    A, B, th3, th4 = fourbar(a, b, c, d, th2, side=+1)
    m = {"input": 0.06, "coupler": 0.04, "output": 0.065}
    amp = 70.0
    txt = f"""
double-rocker.yaml — non-Grashof four-bar (a triple rocker): no link turns fully.

Source: chosen for this project.
  Links (mm): ground A0B0 d = {num(d)}, input A0A a = {num(a)}, coupler AB b = {num(b)}, output B0B c = {num(c)}.
  Grashof: s + l = {num(s)} + {num(l)} = {num(s + l)} > p + q = {num(p)} + {num(q)} = {num(p + q)} -> non-Grashof, triple rocker.
  Masses 1 g/mm, uniform slender rods (com mid-length, I = m L^2/12, kg mm^2).
Frames: local x from first joint to second (input A0->A, coupler A->B, output B0->B).
Design pose: input angle 0 deg (A on the ground line at [60, 0]), B above the line A->B0
  (side +1); closed to ~1e-13 mm.

Facts tests rely on:
  - 3 moving bodies, 4 revolutes: n = 9, n_c = 8, Grubler 1, DOF 1 (rank 8) everywhere: the
    limits below are dead points of an input driver, not change points; no redundant equation.
  - Input range: the input oscillates between -{th_lim:.6f} and +{th_lim:.6f} deg. Both limits are
    the positions where coupler and output are collinear and extended (|B0A| = b + c = {num(b + c)}):
    cos(theta) = (a^2 + d^2 - (b + c)^2)/(2 a d) = {cos_lim:.12f}. The folded alignment
    |B0A| = c - b = {num(c - b)} is unreachable (a + {num(c - b)} < d). These are dead points when the linkage
    is driven from the input (d^T F -> 0 there). A non-Grashof linkage has a single circuit that
    holds both assembly modes: a motion carried through a limit continues in the other mode
    (B on the other side of the line A->B0).
  - Output range: between {th_o:.6f} and {360 - th_o:.6f} deg (input and coupler collinear and
    extended, |A0B| = a + b = {num(a + b)}; dead points when driven from the output).
  - Driver: harmonic, input = {num(amp)} deg * sin(2 pi * 1 Hz * t) (stays inside the +-{th_lim:.3f} deg
    range; a constant-speed driver would stop at the first dead point).
  - Measures: input_angle, output_angle (joint angles, deg), coupler_angle, B_x, B_y (mm).
"""
    lines = header(txt)
    lines += [
        "orthomech: 1",
        "name: double-rocker",
        'description: "Non-Grashof four-bar (triple rocker) 100/60/40/65 mm, input range +-77.6 deg"',
        MM,
        "ground:",
        f"  points: {pts({'A0': (0, 0), 'B0': (d, 0)})}",
        "bodies:",
    ]
    lines += body_block("input", m["input"], (0, 0, DEG_IN[th2]), {"A0": (0, 0), "A": (a, 0)},
                        rod_inertia(m["input"], a), (a / 2, 0))
    lines += body_block("coupler", m["coupler"], (A[0], A[1], deg(th3)), {"A": (0, 0), "B": (b, 0)},
                        rod_inertia(m["coupler"], b), (b / 2, 0))
    lines += body_block("output", m["output"], (d, 0, deg(th4)), {"B0": (0, 0), "B": (c, 0)},
                        rod_inertia(m["output"], c), (c / 2, 0))
    lines += [
        "joints:",
        "  - {name: A0, type: revolute, connects: [ground.A0, input.A0]}",
        "  - {name: A, type: revolute, connects: [input.A, coupler.A]}",
        "  - {name: B, type: revolute, connects: [coupler.B, output.B]}",
        "  - {name: B0, type: revolute, connects: [ground.B0, output.B0]}",
        "loads:",
        G_MM + "   # mm/s^2",
        "measures:",
        "  - {name: input_angle, type: joint, joint: A0}",
        "  - {name: output_angle, type: joint, joint: B0}",
        "  - {name: coupler_angle, type: angle, body: coupler}",
        "  - {name: B_x, type: point, point: coupler.B, component: x}",
        "  - {name: B_y, type: point, point: coupler.B, component: y}",
        "drivers:",
        f"  - {{name: rock, joint: A0, profile: harmonic, initial: 0, amplitude: {num(amp)}, frequency: 1}}",
        "analysis: {driver: rock, steps: 360}",
    ]
    write("double-rocker.yaml", lines)
    return dict(th_lim=th_lim, th_o=th_o)


# ---------------------------------------------------------------------------------------------
# 3. slider-crank
def gen_slider_crank():
    r, l = 50.0, 200.0
    th2 = rad_in(45)
    A = mul(r, u(th2))
    xB = r * math.cos(th2) + math.sqrt(l * l - (r * math.sin(th2)) ** 2)
    B = (xB, 0.0)
    th3 = ang(sub(B, A))
    hc = (2 * r) / (10.0 - 1.0)  # clearance height for compression ratio 10
    n_poly = 1.3
    svals = [100, 80, 60, 40, 30, 20, 10, 5, 2, 0]
    tab = []
    for sv in svals:
        f = (hc / (hc + sv)) ** n_poly
        tab.append((r + l - sv, round(f, 4)))
    m = {"crank": 0.5, "rod": 0.6, "piston": 0.4}
    I_piston = 200.0
    bore = 50.0
    area = math.pi * bore * bore / 4.0
    pmax = 2000.0 / area  # N/mm^2 = MPa
    txt = f"""
slider-crank.yaml — in-line slider-crank (engine-like): crank, connecting rod, piston.

Source: chosen for this project. Crank radius r = {num(r)} mm, connecting rod l = {num(l)} mm (l/r = 4),
  in line: the cylinder axis passes through the crank axis O (ground point X = O = [0, 0]).
  Masses: crank {num(m['crank'])} kg, rod {num(m['rod'])} kg as uniform slender rods (com mid-length, I = m L^2/12);
  piston {num(m['piston'])} kg, inertia {num(I_piston)} kg mm^2 (nominal: the piston does not rotate).
  Gas force: a polytropic pressure x area profile, F = 2000 N * (h_c/(h_c + s))^1.3, s = distance
  of the piston from top dead centre (s = 250 - piston_x), clearance height h_c = 2r/(CR - 1)
  = {hc:.4f} mm for a compression ratio CR = 10: 2000 N at TDC ({pmax * 10:.2f} bar on a {num(bore)} mm bore),
  {2000 * (hc / (hc + 100)) ** n_poly:.1f} N at BDC. The table is against the measure piston_x (mm).
  Sign: the force is [-2000, 0] N in the world frame times the table factor, i.e. always along
  -x, toward the crank (the gas pushes the piston toward the crankshaft). Because the table
  depends on the position only, the same force acts on both strokes: it opposes the motion
  while the piston moves away from the crank (compression) and drives it while the piston moves
  toward the crank (expansion); its net work over a revolution is zero (a conservative
  idealisation, not a four-stroke cycle).
Frames: crank O->A, rod A->B (B = wrist pin), piston frame at B with x along the cylinder axis.
  The prismatic joint `slide` connects [ground.X, piston.B] with axis [1, 0] (ground frame); its
  joint measure piston_x = axis^T (r_B - r_X) = x of the wrist pin: {num(r + l)} mm at TDC, {num(l - r)} mm at BDC.
Design pose: crank angle 45 deg, piston_x = r cos + sqrt(l^2 - r^2 sin^2) = {xB!r} mm.

Facts tests rely on:
  - 3 moving bodies, 3 revolutes + 1 prismatic: n = 9, n_c = 2 + 2 + 2 + 2 = 8, Grubler 1, DOF 1.
  - Stroke 2r = {num(2 * r)} mm: TDC at crank 0 deg (piston_x = {num(r + l)}), BDC at crank 180 deg (piston_x = {num(l - r)});
    both are dead points when driven from the piston, none when driven from the crank.
  - Driver: crank at 3000 rpm (joint O). At constant crank speed w the piston velocity is
    dx/dt = -r w sin(th) (1 + r cos(th)/sqrt(l^2 - r^2 sin^2(th))).
  - Measures: crank_angle (deg), piston_x (mm), piston_v (mm/s), piston_a (mm/s^2), rod_angle (deg).
"""
    lines = header(txt)
    lines += [
        "orthomech: 1",
        "name: slider-crank",
        'description: "In-line slider-crank r = 50 mm, l = 200 mm, gas force vs stroke, crank at 3000 rpm"',
        MM,
        "ground:",
        f"  points: {pts({'O': (0, 0), 'X': (0, 0)})}",
        "bodies:",
    ]
    lines += body_block("crank", m["crank"], (0, 0, DEG_IN[th2]), {"O": (0, 0), "A": (r, 0)},
                        rod_inertia(m["crank"], r), (r / 2, 0))
    lines += body_block("rod", m["rod"], (A[0], A[1], deg(th3)), {"A": (0, 0), "B": (l, 0)},
                        rod_inertia(m["rod"], l), (l / 2, 0))
    lines += body_block("piston", m["piston"], (B[0], B[1], 0), {"B": (0, 0)}, I_piston, (0, 0),
                        outline=[(-20, -25), (20, -25), (20, 25), (-20, 25), (-20, -25)])
    lines += [
        "joints:",
        "  - {name: O, type: revolute, connects: [ground.O, crank.O]}",
        "  - {name: A, type: revolute, connects: [crank.A, rod.A]}",
        "  - {name: B, type: revolute, connects: [rod.B, piston.B]}",
        "  - {name: slide, type: prismatic, connects: [ground.X, piston.B], axis: [1, 0]}",
        "loads:",
        G_MM + "   # mm/s^2",
        "  - name: gas",
        "    type: force",
        "    point: piston.B",
        "    force: [-2000, 0]   # N, world frame: toward the crank",
        "    frame: world",
        "    # [piston_x in mm, factor]: factor = (h_c/(h_c + s))^1.3, s = 250 - piston_x",
        f"    table: {{measure: piston_x, points: {table(tab)}}}",
        "measures:",
        "  - {name: crank_angle, type: joint, joint: O}",
        "  - {name: piston_x, type: joint, joint: slide}",
        "  - {name: piston_v, type: joint, joint: slide, derivative: 1}",
        "  - {name: piston_a, type: joint, joint: slide, derivative: 2}",
        "  - {name: rod_angle, type: angle, body: rod}",
        "drivers:",
        "  - {name: motor, joint: O, speed: 3000 rpm}",
        "analysis: {driver: motor, steps: 360}",
    ]
    write("slider-crank.yaml", lines)
    return dict(xB=xB, table=tab)


# ---------------------------------------------------------------------------------------------
# 4. Watt II six-bar
def gen_watt():
    a, b, c, d = 30.0, 80.0, 60.0, 70.0
    Cl = (20.0, -45.0)           # C on the ternary rocker, rocker frame
    D0 = (150.0, 40.0)
    l5, l6 = 50.0, 40.0          # C–D link, output D0–D
    th2 = rad_in(60)
    A, B, th3, th4 = fourbar(a, b, c, d, th2)
    B0 = (d, 0.0)
    C = add(B0, rot(th4, Cl))
    D = circle_cut(C, l5, D0, l6, +1)
    th5 = ang(sub(D, C))
    th6 = ang(sub(D, D0))
    # sweep: transmission angle at D and output range
    mus, outs = [], []
    for k in range(3600):
        t = math.radians(k / 10)
        Ak, Bk, _, t4 = fourbar(a, b, c, d, t)
        Ck = add(B0, rot(t4, Cl))
        Dk = circle_cut(Ck, l5, D0, l6, +1)
        mus.append(interior_angle_deg(sub(Ck, Dk), sub(D0, Dk)))
        outs.append(deg(ang(sub(Dk, D0))))
    tri = [(0.0, 0.0), (c, 0.0), Cl]
    m_t = 0.12
    com_t = centroid(tri)
    I_t = plate_inertia(m_t, tri)
    m = {"crank": 0.03, "coupler": 0.08, "link": 0.05, "output": 0.04}
    s, l, p, q = grashof([a, b, c, d])
    txt = f"""
watt-six-bar.yaml — Watt II six-bar: two four-bars in series sharing the ternary rocker.

Source: chosen for this project.
  Ground (ternary): A0 = [0, 0], B0 = [{num(d)}, 0], D0 = {vec(D0)} mm.
  Loop 1 (crank-rocker): crank A0A = {num(a)}, coupler AB = {num(b)}, rocker B0B = {num(c)}, ground A0B0 = {num(d)};
    Grashof s + l = {num(s)} + {num(l)} = {num(s + l)} <= p + q = {num(p)} + {num(q)} = {num(p + q)}, crank shortest and grounded
    -> crank-rocker (the same proportions as crank-rocker.yaml).
  Ternary rocker (B0, B, C): B0 = [0, 0], B = [{num(c)}, 0], C = {vec(Cl)} in its frame (a bell crank;
    sides B0B = {num(c)}, B0C = {norm(Cl):.4f}, BC = {norm(sub(Cl, (c, 0))):.4f} mm).
  Loop 2: link CD = {num(l5)}, output D0D = {num(l6)}; D on the side +1 (left of C->D0).
  Masses (binary links 1 g/mm): crank {num(m['crank'])}, coupler {num(m['coupler'])}, link {num(m['link'])}, output {num(m['output'])} kg,
    uniform slender rods (com mid-length, I = m L^2/12). Ternary rocker: a thin uniform triangular
    plate of {num(m_t)} kg, com at the centroid {vec((round(com_t[0], 6), round(com_t[1], 6)))}, I = m (a^2 + b^2 + c^2)/36 = {I_t:.6f} kg mm^2.
Frames: crank A0->A, coupler A->B, rocker B0->B (C off-axis), link C->D, output D0->D.
Design pose: crank angle 60 deg, both loops in the assembly mode above (B above A0B0, D side +1);
  closed to ~1e-13 mm.

Facts tests rely on:
  - 5 moving bodies, 7 revolutes: n = 15, n_c = 14, Grubler 1, DOF 1 (rank 14) over the whole
    crank revolution; no redundant equation.
  - Over a crank revolution (0.1 deg sampling): transmission angle at D (between D->C and D->D0)
    stays in [{min(mus):.2f}, {max(mus):.2f}] deg, output angle in [{min(outs):.2f}, {max(outs):.2f}] deg.
    No dead point when driven from the crank.
  - Driver: crank at 300 rpm (joint A0).
  - Measures: crank_angle, rocker_angle, output_angle (joint angles, deg), D_x, D_y (mm).
"""
    lines = header(txt)
    lines += [
        "orthomech: 1",
        "name: watt-six-bar",
        'description: "Watt II six-bar: crank-rocker A0-A-B-B0 in series with four-bar B0-C-D-D0"',
        MM,
        "ground:",
        f"  points: {pts({'A0': (0, 0), 'B0': (d, 0), 'D0': D0})}",
        "bodies:",
    ]
    lines += body_block("crank", m["crank"], (0, 0, DEG_IN[th2]), {"A0": (0, 0), "A": (a, 0)},
                        rod_inertia(m["crank"], a), (a / 2, 0))
    lines += body_block("coupler", m["coupler"], (A[0], A[1], deg(th3)), {"A": (0, 0), "B": (b, 0)},
                        rod_inertia(m["coupler"], b), (b / 2, 0))
    lines += body_block("rocker", m_t, (B0[0], B0[1], deg(th4)), {"B0": (0, 0), "B": (c, 0), "C": Cl},
                        I_t, com_t, outline=[(0, 0), (c, 0), Cl, (0, 0)],
                        notes=["ternary: thin triangular plate, com at the centroid"])
    lines += body_block("link", m["link"], (C[0], C[1], deg(th5)), {"C": (0, 0), "D": (l5, 0)},
                        rod_inertia(m["link"], l5), (l5 / 2, 0))
    lines += body_block("output", m["output"], (D0[0], D0[1], deg(th6)), {"D0": (0, 0), "D": (l6, 0)},
                        rod_inertia(m["output"], l6), (l6 / 2, 0))
    lines += [
        "joints:",
        "  - {name: A0, type: revolute, connects: [ground.A0, crank.A0]}",
        "  - {name: A, type: revolute, connects: [crank.A, coupler.A]}",
        "  - {name: B, type: revolute, connects: [coupler.B, rocker.B]}",
        "  - {name: B0, type: revolute, connects: [ground.B0, rocker.B0]}",
        "  - {name: C, type: revolute, connects: [rocker.C, link.C]}",
        "  - {name: D, type: revolute, connects: [link.D, output.D]}",
        "  - {name: D0, type: revolute, connects: [ground.D0, output.D0]}",
        "loads:",
        G_MM + "   # mm/s^2",
        "measures:",
        "  - {name: crank_angle, type: joint, joint: A0}",
        "  - {name: rocker_angle, type: joint, joint: B0}",
        "  - {name: output_angle, type: joint, joint: D0}",
        "  - {name: D_x, type: point, point: output.D, component: x}",
        "  - {name: D_y, type: point, point: output.D, component: y}",
        "drivers:",
        "  - {name: motor, joint: A0, speed: 300 rpm}",
        "analysis: {driver: motor, steps: 360}",
    ]
    write("watt-six-bar.yaml", lines)
    return dict(mu=(min(mus), max(mus)), out=(min(outs), max(outs)))


# ---------------------------------------------------------------------------------------------
# 5. Stephenson III six-bar
def gen_stephenson():
    a, b, c, d = 30.0, 80.0, 60.0, 70.0
    Cl = (40.0, 30.0)            # C on the ternary coupler, coupler frame
    D0 = (20.0, 120.0)
    l5, l6 = 60.0, 60.0          # C–D link, output D0–D
    side2 = -1
    th2 = rad_in(60)
    A, B, th3, th4 = fourbar(a, b, c, d, th2)
    C = add(A, rot(th3, Cl))
    D = circle_cut(C, l5, D0, l6, side2)
    th5 = ang(sub(D, C))
    th6 = ang(sub(D, D0))
    mus, outs, dists = [], [], []
    for k in range(3600):
        t = math.radians(k / 10)
        Ak, Bk, t3, _ = fourbar(a, b, c, d, t)
        Ck = add(Ak, rot(t3, Cl))
        Dk = circle_cut(Ck, l5, D0, l6, side2)
        mus.append(interior_angle_deg(sub(Ck, Dk), sub(D0, Dk)))
        outs.append(deg(ang(sub(Dk, D0))))
        dists.append(norm(sub(Ck, D0)))
    tri = [(0.0, 0.0), (b, 0.0), Cl]
    m_t = 0.1
    com_t = centroid(tri)
    I_t = plate_inertia(m_t, tri)
    m = {"crank": 0.03, "rocker": 0.06, "link": 0.06, "output": 0.06}
    s, l, p, q = grashof([a, b, c, d])
    txt = f"""
stephenson-six-bar.yaml — Stephenson III six-bar: a crank-rocker whose ternary coupler drives a
dyad C-D-D0 to the ground.

Source: chosen for this project.
  Ground (ternary): A0 = [0, 0], B0 = [{num(d)}, 0], D0 = {vec(D0)} mm.
  Four-bar: crank A0A = {num(a)}, ternary coupler AB = {num(b)}, rocker B0B = {num(c)}, ground A0B0 = {num(d)};
    Grashof s + l = {num(s)} + {num(l)} = {num(s + l)} <= p + q = {num(p)} + {num(q)} = {num(p + q)}, crank shortest and grounded
    -> crank-rocker.
  Ternary coupler (A, B, C): A = [0, 0], B = [{num(b)}, 0], C = {vec(Cl)} in its frame (sides AB = {num(b)},
    AC = {norm(Cl):.4f}, BC = {norm(sub(Cl, (b, 0))):.4f} mm).
  Dyad: link CD = {num(l5)}, output D0D = {num(l6)}; D on side -1 (right of C->D0). Over a crank
    revolution |D0C| stays in [{min(dists):.3f}, {max(dists):.3f}] inside (|l5 - l6|, l5 + l6) = (0, 120), so
    the dyad always closes.
  Masses: crank {num(m['crank'])}, rocker {num(m['rocker'])}, link {num(m['link'])}, output {num(m['output'])} kg, uniform slender rods
    (com mid-length, I = m L^2/12). Ternary coupler: thin uniform triangular plate of {num(m_t)} kg,
    com at the centroid {vec((round(com_t[0], 6), round(com_t[1], 6)))}, I = m (a^2 + b^2 + c^2)/36 = {I_t:.6f} kg mm^2.
Frames: crank A0->A, coupler A->B (C off-axis), rocker B0->B, link C->D, output D0->D.
Design pose: crank angle 60 deg, B above A0B0, D side -1; closed to ~1e-13 mm.

Facts tests rely on:
  - 5 moving bodies, 7 revolutes: n = 15, n_c = 14, Grubler 1, DOF 1 (rank 14) over the whole
    crank revolution; no redundant equation.
  - Over a crank revolution (0.1 deg sampling): transmission angle at D in [{min(mus):.2f}, {max(mus):.2f}] deg,
    output angle in [{min(outs):.2f}, {max(outs):.2f}] deg. No dead point when driven from the crank.
  - Driver: crank at 300 rpm (joint A0).
  - Measures: crank_angle, output_angle (joint angles, deg), coupler_angle, C_x, C_y (coupler
    point C, mm).
"""
    lines = header(txt)
    lines += [
        "orthomech: 1",
        "name: stephenson-six-bar",
        'description: "Stephenson III six-bar: crank-rocker with ternary coupler driving dyad C-D-D0"',
        MM,
        "ground:",
        f"  points: {pts({'A0': (0, 0), 'B0': (d, 0), 'D0': D0})}",
        "bodies:",
    ]
    lines += body_block("crank", m["crank"], (0, 0, DEG_IN[th2]), {"A0": (0, 0), "A": (a, 0)},
                        rod_inertia(m["crank"], a), (a / 2, 0))
    lines += body_block("coupler", m_t, (A[0], A[1], deg(th3)), {"A": (0, 0), "B": (b, 0), "C": Cl},
                        I_t, com_t, outline=[(0, 0), (b, 0), Cl, (0, 0)],
                        notes=["ternary: thin triangular plate, com at the centroid"])
    lines += body_block("rocker", m["rocker"], (d, 0, deg(th4)), {"B0": (0, 0), "B": (c, 0)},
                        rod_inertia(m["rocker"], c), (c / 2, 0))
    lines += body_block("link", m["link"], (C[0], C[1], deg(th5)), {"C": (0, 0), "D": (l5, 0)},
                        rod_inertia(m["link"], l5), (l5 / 2, 0))
    lines += body_block("output", m["output"], (D0[0], D0[1], deg(th6)), {"D0": (0, 0), "D": (l6, 0)},
                        rod_inertia(m["output"], l6), (l6 / 2, 0))
    lines += [
        "joints:",
        "  - {name: A0, type: revolute, connects: [ground.A0, crank.A0]}",
        "  - {name: A, type: revolute, connects: [crank.A, coupler.A]}",
        "  - {name: B, type: revolute, connects: [coupler.B, rocker.B]}",
        "  - {name: B0, type: revolute, connects: [ground.B0, rocker.B0]}",
        "  - {name: C, type: revolute, connects: [coupler.C, link.C]}",
        "  - {name: D, type: revolute, connects: [link.D, output.D]}",
        "  - {name: D0, type: revolute, connects: [ground.D0, output.D0]}",
        "loads:",
        G_MM + "   # mm/s^2",
        "measures:",
        "  - {name: crank_angle, type: joint, joint: A0}",
        "  - {name: output_angle, type: joint, joint: D0}",
        "  - {name: coupler_angle, type: angle, body: coupler}",
        "  - {name: C_x, type: point, point: coupler.C, component: x}",
        "  - {name: C_y, type: point, point: coupler.C, component: y}",
        "drivers:",
        "  - {name: motor, joint: A0, speed: 300 rpm}",
        "analysis: {driver: motor, steps: 360}",
    ]
    write("stephenson-six-bar.yaml", lines)
    return dict(mu=(min(mus), max(mus)), out=(min(outs), max(outs)))


# ---------------------------------------------------------------------------------------------
# 6. quick-return (crank-shaper)
def gen_quick_return():
    O4 = (0.0, 0.0)
    dO = 200.0
    O2 = (0.0, dO)
    r = 80.0
    L = 500.0
    lk = 150.0
    yr = 500.0
    th2 = rad_in(0)
    A = add(O2, mul(r, u(th2)))
    psi = ang(sub(A, O4))
    B = add(O4, mul(L, u(psi)))
    Cx = B[0] + math.sqrt(lk * lk - (yr - B[1]) ** 2)
    C = (Cx, yr)
    th5 = ang(sub(C, B))
    sA = norm(sub(A, O4))  # position of the pin along the slot at the design
    half = math.asin(r / dO)
    # lever extremes: crank perpendicular to the lever (lever tangent to the crank circle)
    ext = []
    for psi_e in (math.pi / 2 - half, math.pi / 2 + half):
        ue = u(psi_e)
        Ae = mul(dot(O2, ue), ue)
        the = wrap360(deg(ang(sub(Ae, O2))))
        Be = mul(L, ue)
        Cxe = Be[0] + math.sqrt(lk * lk - (yr - Be[1]) ** 2)
        ext.append((deg(psi_e), the, Cxe))
    slow = 180.0 + 2 * deg(half)
    fast = 180.0 - 2 * deg(half)
    ratio = slow / fast
    # numerical confirmation of the ram extremes
    best_min, best_max = (1e9, None), (-1e9, None)
    for k in range(360000):
        t = math.radians(k / 1000)
        Ak = add(O2, mul(r, u(t)))
        Bk = mul(L, u(ang(Ak)))
        x = Bk[0] + math.sqrt(lk * lk - (yr - Bk[1]) ** 2)
        if x < best_min[0]:
            best_min = (x, k / 1000)
        if x > best_max[0]:
            best_max = (x, k / 1000)
    stroke = best_max[0] - best_min[0]
    m = {"crank": 0.5, "lever": 2.5, "link": 0.5, "ram": 10.0}
    I_ram = 10.0 * (400.0 ** 2 + 100.0 ** 2) / 12.0
    txt = f"""
quick-return.yaml — crank-shaper quick-return mechanism (oscillating slotted lever, Whitworth-like):
the crank pin A slides in a slot along the lever; the lever drives the ram through a link.

Source: chosen for this project (textbook crank-shaper proportions).
  Ground: lever pivot O4 = [0, 0], crank pivot O2 = [0, {num(dO)}] (O2O4 = d = {num(dO)} mm), ram line y = {num(yr)} mm
  (ground point R = [0, {num(yr)}]). Crank O2A r = {num(r)}; lever O4B = {num(L)} (the slot is the lever's
  local x axis through O4); link BC = {num(lk)}; ram pinned to the link at C, sliding along x.
  r < d, so the crank turns fully and the lever oscillates (crank-shaper; with r > d it would be
  a Whitworth drive). The slot must hold the pin: |O4A| ranges over [d - r, d + r] = [{num(dO - r)}, {num(dO + r)}] < {num(L)}.
  Masses: crank {num(m['crank'])}, lever {num(m['lever'])}, link {num(m['link'])} kg as uniform slender rods (com mid-length,
  I = m L^2/12); ram {num(m['ram'])} kg, a 400 x 100 mm block: I = m (400^2 + 100^2)/12 = {I_ram:.4f} kg mm^2.
  The sliding block of the crank pin is massless (modelled by the pin-in-slot joint).
Joints: pin-in-slot `slot` connects [lever.O4, crank.A], axis [1, 0] in the lever frame: the pin A
  of the crank stays on the line through O4 along the lever (1 row).
Design pose: crank angle 0 deg (A = [{num(r)}, {num(dO)}]), lever angle atan2({num(dO)}, {num(r)}) = {deg(psi):.6f} deg, pin at
  {sA:.6f} mm along the slot; closed to ~1e-13 mm.

Facts tests rely on:
  - Bodies crank, lever, link, ram: n = 12; rows: revolute O2 2 + revolute O4 2 + pin-in-slot 1 +
    revolute B 2 + revolute C 2 + prismatic slide 2 = 11; Grubler 1, DOF 1.
  - Lever (and ram) extremes where the crank is perpendicular to the lever (lever tangent to the
    crank circle), lever at 90 -+ asin(r/d) = 90 -+ {deg(half):.6f} deg from +x:
      lever {ext[0][0]:.6f} deg (ram right, x_C = {ext[0][2]:.6f} mm) at crank {ext[0][1]:.6f} deg,
      lever {ext[1][0]:.6f} deg (ram left,  x_C = {ext[1][2]:.6f} mm) at crank {ext[1][1]:.6f} deg.
    Ram stroke {stroke:.6f} mm (numerical sweep: min at crank {best_min[1]:.3f}, max at {best_max[1]:.3f} deg).
  - Quick-return time ratio = (180 + 2 asin(r/d)) / (180 - 2 asin(r/d)) = {slow:.6f} / {fast:.6f}
    = {ratio:.6f}. With the crank turning counter-clockwise (positive speed) the slow (working)
    stroke is the ram moving toward -x (crank on its upper arc, {ext[0][1] - 360:.3f} -> {ext[1][1]:.3f} deg), the
    quick return is toward +x.
  - Driver: crank at 60 rpm (joint O2): the working stroke takes {slow / 360:.6f} s, the return {fast / 360:.6f} s.
  - Measures: crank_angle, lever_angle (deg), ram_x (mm, joint measure of the prismatic joint:
    x of C), ram_v (mm/s), slot_position (distance O4-A, mm).
"""
    lines = header(txt)
    lines += [
        "orthomech: 1",
        "name: quick-return",
        'description: "Crank-shaper quick-return: crank 80, O2O4 200, slotted lever 500, link 150 mm; time ratio 1.71"',
        MM,
        "ground:",
        f"  points: {pts({'O2': O2, 'O4': O4, 'R': (0, yr)})}",
        "bodies:",
    ]
    lines += body_block("crank", m["crank"], (O2[0], O2[1], DEG_IN[th2]), {"O2": (0, 0), "A": (r, 0)},
                        rod_inertia(m["crank"], r), (r / 2, 0))
    lines += body_block("lever", m["lever"], (0, 0, deg(psi)), {"O4": (0, 0), "B": (L, 0)},
                        rod_inertia(m["lever"], L), (L / 2, 0))
    lines += body_block("link", m["link"], (B[0], B[1], deg(th5)), {"B": (0, 0), "C": (lk, 0)},
                        rod_inertia(m["link"], lk), (lk / 2, 0))
    lines += body_block("ram", m["ram"], (C[0], C[1], 0), {"C": (0, 0)}, I_ram, (0, 0),
                        outline=[(-200, 0), (200, 0), (200, 100), (-200, 100), (-200, 0)])
    lines += [
        "joints:",
        "  - {name: O2, type: revolute, connects: [ground.O2, crank.O2]}",
        "  - {name: O4, type: revolute, connects: [ground.O4, lever.O4]}",
        "  - {name: slot, type: pin-in-slot, connects: [lever.O4, crank.A], axis: [1, 0]}",
        "  - {name: B, type: revolute, connects: [lever.B, link.B]}",
        "  - {name: C, type: revolute, connects: [link.C, ram.C]}",
        "  - {name: slide, type: prismatic, connects: [ground.R, ram.C], axis: [1, 0]}",
        "loads:",
        G_MM + "   # mm/s^2",
        "measures:",
        "  - {name: crank_angle, type: joint, joint: O2}",
        "  - {name: lever_angle, type: joint, joint: O4}",
        "  - {name: ram_x, type: joint, joint: slide}",
        "  - {name: ram_v, type: joint, joint: slide, derivative: 1}",
        "  - {name: slot_position, type: distance, points: [lever.O4, crank.A]}",
        "drivers:",
        "  - {name: motor, joint: O2, speed: 60 rpm}",
        "analysis: {driver: motor, steps: 360}",
    ]
    write("quick-return.yaml", lines)
    return dict(ratio=ratio, ext=ext, stroke=stroke, half=deg(half))


# ---------------------------------------------------------------------------------------------
# 7. IFToMM A02 N four-bar
def gen_n_four_bar(N):
    g = 9.81
    T0 = (N + 1) / 6.0 + N / 2.0
    V0 = (N + 1) * 1.0 * g * 0.5 + N * 1.0 * g * 1.0
    txt = f"""
n-four-bar-{N}.yaml — IFToMM benchmark A02, the N four-bar mechanism, with N = {N}.

Source: IFToMM Library of Computational Benchmark Problems, problem A02 (N four-bar mechanism,
  singular positions). Generated by scripts/gen_mechanisms.py.
  N + 1 = {N + 1} vertical links link0..link{N}, each 1 m, 1 kg, uniform rod (com at mid-length,
  I = 1/12 kg m^2), pinned to the ground at (k, 0), k = 0..{N}; N = {N} horizontal couplers
  coupler0..coupler{N - 1} (1 m, 1 kg, I = 1/12); coupler k joins the tops B of link k and link k+1
  at y = 1. Gravity 9.81 m/s^2 in -y. Units SI.
Frames: link k: origin at its ground pivot O = [0, 0], local x up along the link (pose angle pi/2),
  top B = [1, 0]. Coupler k: origin at the top of link k, local x along +x, points L = [0, 0]
  (on link k) and R = [1, 0] (on link k+1).
Joints: O{{k}} = [ground.O{{k}}, link{{k}}.O]; L{{k}} = [coupler{{k}}.L, link{{k}}.B]; R{{k}} = [coupler{{k}}.R, link{{k+1}}.B].

Benchmark initial condition: this position, with the top of the first link B0 = (0, 1) moving
  at x' = 1 m/s: every link turns at -1 rad/s (clockwise), every coupler translates at 1 m/s
  along +x: `initial: {{rates: {{B0_x: 1}}}}` below, so that `orthomech simulate` reproduces the
  benchmark with no option (`--rate` replaces it). Simulate 10 s (N = 2) or 20 s (N = 40).
  Initial kinetic energy T0 = (N + 1)/6 + N/2 = {T0!r} J; potential energy (zero at y = 0)
  V0 = 9.81 ((N + 1)/2 + N) = {V0!r} J.

Facts tests rely on:
  - {2 * N + 1} moving bodies, {3 * N + 1} revolutes: n = {3 * (2 * N + 1)}, n_c = {2 * (3 * N + 1)}, Grubler 1, DOF 1 (rank {2 * (3 * N + 1)})
    at this position; no redundant equation.
  - All links rotate fully. Twice per revolution the mechanism passes the horizontal position
    (all links along the x axis), a change point where rank E drops and the instantaneous DOF
    jumps from 1 to N + 1 = {N + 1}. The solution must stay on the parallelogram branch (every link
    parallel to link0, every coupler horizontal) and conserve energy.
  - Measures: B0_x, B0_y (top of link0), B0_vx, B0_vy (its velocity). Reference output is the
    position and velocity of B0 over time.
"""
    lines = header(txt)
    gp = {f"O{k}": (k, 0) for k in range(N + 1)}
    lines += [
        "orthomech: 1",
        f"name: n-four-bar-{N}",
        f'description: "IFToMM A02 N four-bar mechanism, N = {N}: {N + 1} vertical links, {N} couplers"',
        SI,
        "ground:",
        f"  points: {pts(gp)}",
        "bodies:",
    ]
    I = 1.0 / 12.0
    for k in range(N + 1):
        lines += body_block(f"link{k}", 1, (k, 0, math.pi / 2), {"O": (0, 0), "B": (1, 0)}, I, (0.5, 0))
    for k in range(N):
        lines += body_block(f"coupler{k}", 1, (k, 1, 0), {"L": (0, 0), "R": (1, 0)}, I, (0.5, 0))
    lines.append("joints:")
    for k in range(N + 1):
        lines.append(f"  - {{name: O{k}, type: revolute, connects: [ground.O{k}, link{k}.O]}}")
    for k in range(N):
        lines.append(f"  - {{name: L{k}, type: revolute, connects: [coupler{k}.L, link{k}.B]}}")
        lines.append(f"  - {{name: R{k}, type: revolute, connects: [coupler{k}.R, link{k + 1}.B]}}")
    lines += [
        "loads:",
        G_SI,
        "measures:",
        "  - {name: B0_x, type: point, point: link0.B, component: x}",
        "  - {name: B0_y, type: point, point: link0.B, component: y}",
        "  - {name: B0_vx, type: point, point: link0.B, component: x, derivative: 1}",
        "  - {name: B0_vy, type: point, point: link0.B, component: y, derivative: 1}",
        "initial:",
        "  rates: {B0_x: 1}   # the benchmark's initial velocity: B0 moves at x' = 1 m/s",
    ]
    write(f"n-four-bar-{N}.yaml", lines)
    return dict(T0=T0, V0=V0)


# ---------------------------------------------------------------------------------------------
# 8. IFToMM A01 pendulum
def gen_pendulum():
    txt = """
pendulum.yaml — IFToMM benchmark A01, the simple pendulum.

Source: IFToMM Library of Computational Benchmark Problems, problem A01 (Gonzalez, Dopico,
  Lugris, Cuadrado, Multibody System Dynamics 16, 2006).
  Point mass 1 kg (particle P1) on a massless rod of 1 m (a `distance` joint from ground.O to
  P1.origin), gravity 9.81 m/s^2 in -y, released from rest with the rod horizontal: P1 = (-1, 0).
  Units SI. Simulate 2000 s (long-run accuracy and energy test).

Facts tests rely on:
  - 1 particle (n = 2), 1 distance joint (n_c = 1): Grubler 1, DOF 1.
  - Exact solution: sin(theta/2) = k sn(K - sqrt(g/L) t, k^2), k = sin 45 deg, theta from the
    downward vertical; period 2.36784194757623744930329503724 s.
  - Published samples (6 digits): t = 0.5 s: (x, y) = (-0.391049, -0.920370);
    t = 1.0 s: (0.986292, -0.165011).
  - Energy: T + V = 0 with V = m g y (zero at y = 0), constant.
  - Measures: P1_x, P1_y (position), P1_vx, P1_vy (velocity).
"""
    lines = header(txt)
    lines += [
        "orthomech: 1",
        "name: pendulum",
        'description: "IFToMM A01 simple pendulum: 1 kg point mass on a 1 m massless rod"',
        SI,
        "ground:",
        "  points: {O: [0, 0]}",
        "bodies:",
    ]
    lines += body_block("P1", 1, (-1, 0), None, particle=True)
    lines += [
        "joints:",
        "  - {name: rod, type: distance, connects: [ground.O, P1.origin], length: 1}",
        "loads:",
        G_SI,
        "measures:",
        "  - {name: P1_x, type: point, point: P1.origin, component: x}",
        "  - {name: P1_y, type: point, point: P1.origin, component: y}",
        "  - {name: P1_vx, type: point, point: P1.origin, component: x, derivative: 1}",
        "  - {name: P1_vy, type: point, point: P1.origin, component: y, derivative: 1}",
    ]
    write("pendulum.yaml", lines)


# ---------------------------------------------------------------------------------------------
# 8b. A stiff spring-damper pair (the stiff element of IFToMM A05, the stiff flyball governor)
STIFF = dict(m=5.0, I=0.01, k1=1000.0, l1=0.5, k=8e5, c=4e4, l0=0.5, y1=-1.0, y2=-1.51, g=9.81)


def gen_stiff_spring_damper():
    p = STIFF
    mu = p["m"] * p["m"] / (2 * p["m"])  # reduced mass of the pair
    disc = math.sqrt(p["c"] ** 2 - 4 * mu * p["k"])
    fast, slow = (-p["c"] - disc) / (2 * mu), (-p["c"] + disc) / (2 * mu)
    omega = math.sqrt(p["k1"] / (2 * p["m"]))
    txt = f"""
stiff-spring-damper.yaml — two sliders joined by a stiff spring-damper (a stiff ODE).

Source: the stiff element of IFToMM benchmark A05, the stiff flyball governor (IFToMM Library of
  Computational Benchmark Problems, problem A05, M. Gonzalez, Universidade da Coruna, 2005:
  spring-dampers k = 8e5 N/m, c = 4e4 N s/m, rest length 0.5 m, 5 kg point masses), mounted on
  the smallest mechanism that carries it, so that its motion has a closed form.
  Generated by scripts/gen_mechanisms.py. Units SI.
Layout: a vertical guide along the y axis (two prismatic joints to the ground, axis [0, 1]);
  `sleeve` (5 kg) hangs from ground.O = (0, 0) on a soft spring k1 = {num(p["k1"])} N/m, free length
  {num(p["l1"])} m; `bob` (5 kg) hangs below the sleeve on the stiff spring-damper k = 8e5 N/m,
  c = 4e4 N s/m, free length 0.5 m. Gravity 9.81 m/s^2 in -y. Released from rest with the sleeve
  at y1 = {num(p["y1"])} m and the bob at y2 = {num(p["y2"])} m (the stiff spring stretched 1 cm).

Facts tests rely on:
  - 2 bodies (n = 6), 2 prismatic joints (n_c = 4): Grubler 2, DOF 2; the guide keeps both
    springs along y, so the equations are exactly linear:
      m y1'' = k1 (-y1 - l1) - k (y1 - y2 - l0) - c (y1' - y2') - m g
      m y2'' =                 k (y1 - y2 - l0) + c (y1' - y2') - m g
  - Relative motion (reduced mass m/2 = {num(mu)} kg) over-damped: eigenvalues
    {fast:.6g} 1/s (the stiff one) and {slow:.6g} 1/s; the pair moves together on the soft
    spring at about omega = sqrt(k1 / 2m) = {omega:.6g} rad/s (period {2 * math.pi / omega:.6g} s). An explicit
    integrator is held by stability to steps of ~3/{-fast:.4g} s; `--integrator rosenbrock4` by
    accuracy only.
  - Measures: sleeve_y, bob_y, gap (the stiff spring's length), gap_rate.
"""
    lines = header(txt)
    lines += [
        "orthomech: 1",
        "name: stiff-spring-damper",
        'description: "Two sliders joined by the stiff spring-damper of IFToMM A05 (k = 8e5 N/m, c = 4e4 N s/m)"',
        SI,
        "ground:",
        "  points: {O: [0, 0]}",
        "bodies:",
    ]
    lines += body_block("sleeve", p["m"], (0, p["y1"], 0), {"P": (0, 0)}, p["I"])
    lines += body_block("bob", p["m"], (0, p["y2"], 0), {"P": (0, 0)}, p["I"])
    lines += [
        "joints:",
        "  - {name: guide1, type: prismatic, connects: [ground.O, sleeve.P], axis: [0, 1]}",
        "  - {name: guide2, type: prismatic, connects: [ground.O, bob.P], axis: [0, 1]}",
        "loads:",
        G_SI,
        f"  - {{name: soft, type: spring-damper, connects: [ground.O, sleeve.P], stiffness: {num(p['k1'])}, "
        f"free_length: {num(p['l1'])}, damping: 0}}",
        f"  - {{name: stiff, type: spring-damper, connects: [sleeve.P, bob.P], stiffness: {num(p['k'])}, "
        f"free_length: {num(p['l0'])}, damping: {num(p['c'])}}}",
        "measures:",
        "  - {name: sleeve_y, type: point, point: sleeve.P, component: y}",
        "  - {name: bob_y, type: point, point: bob.P, component: y}",
        "  - {name: gap, type: distance, points: [sleeve.P, bob.P]}",
        "  - {name: gap_rate, type: distance, points: [sleeve.P, bob.P], derivative: 1}",
    ]
    write("stiff-spring-damper.yaml", lines)
    return dict(fast=fast, slow=slow, omega=omega)


# ---------------------------------------------------------------------------------------------
# 9. Andrews' squeezing mechanism
ANDREWS = dict(
    m1="0.04325", m2="0.00365", m3="0.02373", m4="0.00706", m5="0.07050", m6="0.00706", m7="0.05498",
    I1="2.194e-6", I2="4.410e-7", I3="5.255e-6", I4="5.667e-7", I5="1.169e-5", I6="5.667e-7",
    I7="1.912e-5",
    xa="-0.06934", ya="-0.00227", xb="-0.03635", yb="0.03273", xc="0.014", yc="0.072",
    c0="4530", mom="0.033", l0="0.07785",
    d="0.028", da="0.0115", e="0.02", ea="0.01421", rr="0.007", ra="0.00092",
    ss="0.035", sa="0.01874", sb="0.01043", sc="0.018", sd="0.02", ta="0.02308", tb="0.00916",
    u="0.04", ua="0.01228", ub="0.00449", zf="0.02", zt="0.04", fa="0.01421",
)
ANDREWS_T0 = dict(
    beta=-0.0617138900142764496358948458001, Theta=0.0, gamma=0.455279819163070380255912382449,
    Phi=0.222668390165885884674473185609, delta=0.487364979543842550225598953530,
    Omega=-0.222668390165885884674473185609, epsilon=1.23054744454982119249735015568,
)


def gen_andrews():
    P = {k: float(v) for k, v in ANDREWS.items()}
    t = ANDREWS_T0
    be, Th, ga, Ph, de, Om, ep = (t[k] for k in ("beta", "Theta", "gamma", "Phi", "delta", "Omega", "epsilon"))
    rr, d, ss, e, zt, zf, uu = P["rr"], P["d"], P["ss"], P["e"], P["zt"], P["zf"], P["u"]
    xa, ya, xb, yb = P["xa"], P["ya"], P["xb"], P["yb"]
    Ap = (xa, ya)
    Bp = (xb, yb)
    poses = {
        "K1": (0.0, 0.0, be),
        "K2": (rr * math.cos(be), rr * math.sin(be), be + Th),
        "K3": (xb, yb, ga),
        "K4": (xa + zt * math.cos(de), ya + zt * math.sin(de), Ph + de),
        "K5": (xa, ya, de),
        "K6": (xa + uu * math.sin(ep), ya - uu * math.cos(ep), Om + ep),
        "K7": (xa, ya, ep),
    }
    # published constraint equations g1..g6 at t = 0 (relative coordinates)
    g = [
        rr * math.cos(be) - d * math.cos(be + Th) - ss * math.sin(ga) - xb,
        rr * math.sin(be) - d * math.sin(be + Th) + ss * math.cos(ga) - yb,
        rr * math.cos(be) - d * math.cos(be + Th) - e * math.sin(Ph + de) - zt * math.cos(de) - xa,
        rr * math.sin(be) - d * math.sin(be + Th) + e * math.cos(Ph + de) - zt * math.sin(de) - ya,
        rr * math.cos(be) - d * math.cos(be + Th) - zf * math.cos(Om + ep) - uu * math.sin(ep) - xa,
        rr * math.sin(be) - d * math.sin(be + Th) - zf * math.sin(Om + ep) + uu * math.cos(ep) - ya,
    ]
    gmax = max(abs(x) for x in g)
    # spring length at t = 0
    xd = P["sd"] * math.cos(ga) + P["sc"] * math.sin(ga) + xb
    yd = P["sd"] * math.sin(ga) - P["sc"] * math.cos(ga) + yb
    Ls = math.hypot(xd - P["xc"], yd - P["yc"])
    A_ = ANDREWS
    txt = f"""
andrews-squeezer.yaml — Andrews' squeezing mechanism (seven-body mechanism), absolute coordinates.

Source: Test Set for IVP Solvers (Univ. Bari, Mazzia & Magherini), problem `andrews`; Hairer &
  Wanner, Solving ODEs II, section VII.7; Schiehlen (ed.), Multibody Systems Handbook, 1990; IFToMM
  benchmark A03. Parameters exactly as published. Units SI.
  7 rigid bodies K1..K7, 10 revolutes, 3 closed loops through the common point E, no gravity;
  driving torque mom = {A_['mom']} N m on the crank K1; a spring c0 = {A_['c0']} N/m, free length l0 = {A_['l0']} m,
  from point D of K3 to the fixed point C. Reference interval t in [0, 0.03] s.
Geometry: derived from the test set's relative-coordinate constraint equations g1..g6 (checked in
  scripts/gen_mechanisms.py) and mass matrix (which fixes the com distances):
  K1 crank: frame at O, angle beta; P = [rr, 0], com [ra, 0].
  K2: frame at P, angle beta + Theta; E = [-d, 0], com [-da, 0].
  K3: frame at B = (xb, yb), angle gamma; E = [0, -ss], spring point D = [sd, -sc], com [sb, -sa].
  K5: frame at A = (xa, ya), angle delta; G = [zt, 0], com [ta, tb].
  K4: frame at G, angle Phi + delta; E = [0, -e], com [0, -(e - ea)].
  K7: frame at A, angle epsilon; H = [0, -u], com [ub, -ua].
  K6: frame at H, angle Omega + epsilon; E = [zf, 0], com [zf - fa, 0].
  Assumption: the published equations fix only the distances sqrt(sa^2 + sb^2), sqrt(ta^2 + tb^2),
  sqrt(ua^2 + ub^2) of the centres of mass of K3, K5, K7 from their pivots (they enter M only as
  m (sa^2 + sb^2) etc., and there is no gravity), not their directions; the directions chosen here
  ([sb, -sa], [ta, tb], [ub, -ua]) do not affect the published angles or multipliers. The com of
  K1 ([ra, 0]), K2, K4, K6 is fixed by the M entries (M11, M12, M45, M67) and used as published.
Design pose: the published consistent values at t = 0,
  beta = {be!r}, Theta = {Th!r}, gamma = {ga!r},
  Phi = {Ph!r}, delta = {de!r}, Omega = {Om!r},
  epsilon = {ep!r} (rad),
  converted to body frames; max |g1..g6| at these angles = {gmax:.1e} m. Spring length at t = 0:
  {Ls!r} m.

Facts tests rely on:
  - 7 bodies (n = 21), 10 revolutes (n_c = 20): Grubler 1, DOF 1 (rank 20); no redundant equation.
  - Joints E23, E24, E26 close the three loops at E; each connects [K2.E, Kj.E], so their rows are
    the published g1,g2 / g3,g4 / g5,g6 and, because the published convention is
    M q'' - f + G^T lambda = 0 while ours is M u' = Q + E lambda (f = point on the first body minus
    point on the second), our multipliers equal MINUS the published ones:
      E23 (x, y) = -(lambda1, lambda2), E24 = -(lambda3, lambda4), E26 = -(lambda5, lambda6).
    At t = 0 (velocities 0): lambda1 = 98.5668703962410896, lambda2 = -6.12268834425566266,
    lambda3..6 = 0; beta'' = 14222.4439199541139, Theta'' = -10666.8329399655854, others 0.
  - Reference state at t = 0.03 s of the Test Set for IVP Solvers, problem andrews (positions rel. 1e-8).
  - Measures (rad): beta (angle of K1), Theta (K2 - K1), gamma (K3), Phi (K4 - K5), delta (K5),
    Omega (K6 - K7), epsilon (K7); spring_length (m).
  - Driver `crank` on the revolute O (ground-K1) is for cycle analysis only (constant 1000 rad/s,
    about the speed the free motion reaches); the benchmark itself is the free motion under the
    torque mom with zero initial velocities.
"""
    lines = header(txt)
    lines += [
        "orthomech: 1",
        "name: andrews-squeezer",
        'description: "Andrews squeezing mechanism (test-set problem andrews, IFToMM A03), 7 bodies, 1 DOF"',
        SI,
        "ground:",
        f"  points: {{O: [0, 0], A: [{A_['xa']}, {A_['ya']}], B: [{A_['xb']}, {A_['yb']}], C: [{A_['xc']}, {A_['yc']}]}}",
        "bodies:",
    ]

    def pose(k):
        return vec(poses[k])

    bodies = [
        ("K1", "m1", "I1", f"[{A_['ra']}, 0]", f"{{O: [0, 0], P: [{A_['rr']}, 0]}}"),
        ("K2", "m2", "I2", f"[-{A_['da']}, 0]", f"{{P: [0, 0], E: [-{A_['d']}, 0]}}"),
        ("K3", "m3", "I3", f"[{A_['sb']}, -{A_['sa']}]",
         f"{{B: [0, 0], E: [0, -{A_['ss']}], D: [{A_['sd']}, -{A_['sc']}]}}"),
        ("K4", "m4", "I4", f"[0, {num(-(P['e'] - P['ea']))}]", f"{{G: [0, 0], E: [0, -{A_['e']}]}}"),
        ("K5", "m5", "I5", f"[{A_['ta']}, {A_['tb']}]", f"{{A: [0, 0], G: [{A_['zt']}, 0]}}"),
        ("K6", "m6", "I6", f"[{num(P['zf'] - P['fa'])}, 0]", f"{{H: [0, 0], E: [{A_['zf']}, 0]}}"),
        ("K7", "m7", "I7", f"[{A_['ub']}, -{A_['ua']}]", f"{{A: [0, 0], H: [0, -{A_['u']}]}}"),
    ]
    for name, mk, ik, com, points in bodies:
        lines += [
            f"  - name: {name}",
            f"    mass: {A_[mk]}",
            f"    inertia: {A_[ik]}",
            f"    com: {com}",
            f"    pose: {pose(name)}",
            f"    points: {points}",
        ]
    lines += [
        "joints:",
        "  - {name: O, type: revolute, connects: [ground.O, K1.O]}",
        "  - {name: P, type: revolute, connects: [K1.P, K2.P]}",
        "  - {name: B, type: revolute, connects: [ground.B, K3.B]}",
        "  - {name: A5, type: revolute, connects: [ground.A, K5.A]}",
        "  - {name: G, type: revolute, connects: [K5.G, K4.G]}",
        "  - {name: A7, type: revolute, connects: [ground.A, K7.A]}",
        "  - {name: H, type: revolute, connects: [K7.H, K6.H]}",
        "  - {name: E23, type: revolute, connects: [K2.E, K3.E]}",
        "  - {name: E24, type: revolute, connects: [K2.E, K4.E]}",
        "  - {name: E26, type: revolute, connects: [K2.E, K6.E]}",
        "loads:",
        f"  - {{name: spring, type: spring-damper, connects: [K3.D, ground.C], stiffness: {A_['c0']}, "
        f"free_length: {A_['l0']}, damping: 0}}",
        f"  - {{name: mom, type: torque, body: K1, torque: {A_['mom']}}}",
        "measures:",
        "  - {name: beta, type: angle, body: K1}",
        "  - {name: Theta, type: angle, bodies: [K1, K2]}",
        "  - {name: gamma, type: angle, body: K3}",
        "  - {name: Phi, type: angle, bodies: [K5, K4]}",
        "  - {name: delta, type: angle, body: K5}",
        "  - {name: Omega, type: angle, bodies: [K7, K6]}",
        "  - {name: epsilon, type: angle, body: K7}",
        "  - {name: spring_length, type: distance, points: [K3.D, ground.C]}",
        "drivers:",
        "  - {name: crank, joint: O, speed: 1000}   # rad/s",
    ]
    write("andrews-squeezer.yaml", lines)
    return dict(gmax=gmax, Ls=Ls)


# ---------------------------------------------------------------------------------------------
# 10. triple crank (redundant parallelogram)
def gen_triple_crank():
    r = 50.0
    th = rad_in(60)
    tip = mul(r, u(th))
    m_c, m_k = 0.2, 0.05
    txt = f"""
triple-crank.yaml — three equal parallel cranks carrying one coupler (a parallelogram with a third
crank): an overconstrained planar linkage with one redundant constraint equation.

Source: chosen for this project (the classic redundant-parallelogram example, design note §3).
  Cranks crank1..crank3, {num(r)} mm, pinned to the ground at x = 0, 100, 200 mm (y = 0); the coupler
  (200 mm) is pinned to their tips at coupler points K1 = [0, 0], K2 = [100, 0], K3 = [200, 0].
  Masses: cranks {num(m_k)} kg, coupler {num(m_c)} kg, uniform slender rods (com mid-length, I = m L^2/12).
Frames: crank k from its ground pivot Ok to its tip; coupler frame at the tip of crank1, x along
  the coupler. Design pose: crank angle 60 deg, coupler horizontal (angle 0) at height
  {tip[1]!r} mm; closed to ~1e-13 mm.

Facts tests rely on:
  - 4 moving bodies (n = 12), 6 revolutes (n_c = 12): Grubler 0, but the real mobility is 1:
    rank E = 11, DOF 1, exactly one redundant equation (which row is named redundant depends
    on the pivoting of the rank-revealing QR; the self-stress below involves all six joints).
  - Self-stress (the null space of E, the indeterminate reaction direction): with the cranks as
    links of equal direction, axial crank forces in the ratio 1 : -2 : 1 (crank1 : crank2 : crank3)
    are in equilibrium on the coupler (sum t_k = 0 and sum t_k x_k = 0 for x = 0, 100, 200).
    Reaction components along that direction are not unique; the minimum-norm lambda is reported.
  - The coupler translates (its angle stays 0) and every crank has the same angle; the tip of
    crank1 (coupler_x, coupler_y) = 50 (cos, sin) of the crank angle.
  - Change points at crank angles 0 and 180 deg (all links collinear with the ground line):
    rank E drops to 10, instantaneous DOF 2.
  - Driver: crank1 at 300 rpm (joint O1). Measures crank1_angle, crank2_angle, crank3_angle (deg),
    coupler_angle (deg), coupler_x, coupler_y (tip of crank1, mm).
"""
    lines = header(txt)
    lines += [
        "orthomech: 1",
        "name: triple-crank",
        'description: "Parallelogram with a third crank: Grubler 0, real DOF 1, one redundant equation"',
        MM,
        "ground:",
        f"  points: {pts({'O1': (0, 0), 'O2': (100, 0), 'O3': (200, 0)})}",
        "bodies:",
    ]
    for k in range(3):
        lines += body_block(f"crank{k + 1}", m_k, (100 * k, 0, DEG_IN[th]), {f"O{k + 1}": (0, 0), "A": (r, 0)},
                            rod_inertia(m_k, r), (r / 2, 0))
    lines += body_block("coupler", m_c, (tip[0], tip[1], 0), {"K1": (0, 0), "K2": (100, 0), "K3": (200, 0)},
                        rod_inertia(m_c, 200.0), (100, 0))
    lines += ["joints:"]
    for k in range(3):
        lines.append(f"  - {{name: O{k + 1}, type: revolute, connects: [ground.O{k + 1}, crank{k + 1}.O{k + 1}]}}")
    for k in range(3):
        lines.append(f"  - {{name: A{k + 1}, type: revolute, connects: [crank{k + 1}.A, coupler.K{k + 1}]}}")
    lines += [
        "loads:",
        G_MM + "   # mm/s^2",
        "measures:",
        "  - {name: crank1_angle, type: joint, joint: O1}",
        "  - {name: crank2_angle, type: joint, joint: O2}",
        "  - {name: crank3_angle, type: joint, joint: O3}",
        "  - {name: coupler_angle, type: angle, body: coupler}",
        "  - {name: coupler_x, type: point, point: coupler.K1, component: x}",
        "  - {name: coupler_y, type: point, point: coupler.K1, component: y}",
        "drivers:",
        "  - {name: motor, joint: O1, speed: 300 rpm}",
        "analysis: {driver: motor, steps: 360}",
    ]
    write("triple-crank.yaml", lines)


# ---------------------------------------------------------------------------------------------
# check: re-read the files, evaluate the joints at the design poses, Grübler, rank
LEN = {"m": 1.0, "cm": 0.01, "mm": 1e-3, "in": 0.0254, "ft": 0.3048}
ANG = {"rad": 1.0, "deg": math.pi / 180.0}


def rank(rows, tol=1e-9):
    A = [list(r) for r in rows]
    if not A:
        return 0
    scale = max(abs(x) for r in A for x in r) or 1.0
    rk, ncol = 0, len(A[0])
    for col in range(ncol):
        piv = max(range(rk, len(A)), key=lambda i: abs(A[i][col]), default=None)
        if piv is None or abs(A[piv][col]) <= tol * scale:
            continue
        A[rk], A[piv] = A[piv], A[rk]
        for i in range(len(A)):
            if i != rk and A[i][col] != 0.0:
                f = A[i][col] / A[rk][col]
                A[i] = [x - f * y for x, y in zip(A[i], A[rk])]
        rk += 1
        if rk == len(A):
            break
    return rk


def check_file(path, override=None):
    import yaml  # test convenience only
    with open(path) as f:
        doc = yaml.safe_load(f)
    units = doc.get("units", {})
    Ls = LEN[units.get("length", "m")]
    As = ANG[units.get("angle", "rad")]
    bodies = doc["bodies"]
    index = {}
    nq = 0
    for b in bodies:
        index[b["name"]] = (nq, b.get("type", "rigid"))
        nq += 2 if b.get("type") == "particle" else 3
    q0 = []
    for b in bodies:
        p = b["pose"]
        q0 += [p[0] * Ls, p[1] * Ls] + ([p[2] * As] if b.get("type") != "particle" else [])
    if override:
        q0 = override(q0)
    gpts = (doc.get("ground") or {}).get("points", {})
    bpts = {b["name"]: b.get("points") or {} for b in bodies}

    def frame(q, bname):
        if bname == "ground":
            return (0.0, 0.0, 0.0)
        o, kind = index[bname]
        return (q[o], q[o + 1], q[o + 2] if kind == "rigid" else 0.0)

    def point(q, ref):
        bname, pname = ref.split(".")
        if bname == "ground":
            p = gpts[pname]
            return (p[0] * Ls, p[1] * Ls)
        s = (0.0, 0.0) if pname == "origin" else tuple(x * Ls for x in bpts[bname][pname])
        x, y, ph = frame(q, bname)
        return add((x, y), rot(ph, s))

    joints = doc.get("joints") or []
    # constants taken from the design poses (angle, length) as the format says
    consts = []
    for j in joints:
        t = j["type"]
        b1, b2 = (r.split(".")[0] for r in j["connects"])
        if t in ("prismatic", "fixed"):
            consts.append(j["angle"] * As if "angle" in j else frame(q0, b2)[2] - frame(q0, b1)[2])
        elif t == "distance":
            consts.append(j["length"] * Ls if "length" in j else
                          norm(sub(point(q0, j["connects"][1]), point(q0, j["connects"][0]))))
        else:
            consts.append(None)

    def residual(q):
        f = []
        for j, c in zip(joints, consts):
            t = j["type"]
            P1, P2 = (point(q, r) for r in j["connects"])
            b1, b2 = (r.split(".")[0] for r in j["connects"])
            if t == "revolute":
                f += list(sub(P1, P2))
            elif t in ("prismatic", "pin-in-slot"):
                ax = rot(frame(q, b1)[2], tuple(j["axis"]))
                n = (-ax[1], ax[0])
                f.append(dot(n, sub(P2, P1)) / norm(n))
                if t == "prismatic":
                    f.append(frame(q, b2)[2] - frame(q, b1)[2] - c)
            elif t == "fixed":
                f += list(sub(P1, P2)) + [frame(q, b2)[2] - frame(q, b1)[2] - c]
            elif t == "distance":
                f.append(norm(sub(P2, P1)) - c)
            else:
                raise ValueError(t)
        return f

    f0 = residual(q0)
    h = 1e-7
    cols = []
    for i in range(nq):
        qp, qm = list(q0), list(q0)
        qp[i] += h
        qm[i] -= h
        cols.append([(a - b) / (2 * h) for a, b in zip(residual(qp), residual(qm))])
    J = [[cols[i][r] for i in range(nq)] for r in range(len(f0))]
    rk = rank(J, 1e-7)
    nc = len(f0)
    return dict(n=nq, nc=nc, grubler=nq - nc, rank=rk, dof=nq - rk,
                resid=max((abs(x) for x in f0), default=0.0) / Ls)


FILES = ["crank-rocker.yaml", "double-rocker.yaml", "slider-crank.yaml", "watt-six-bar.yaml",
         "stephenson-six-bar.yaml", "quick-return.yaml", "n-four-bar-2.yaml", "n-four-bar-40.yaml",
         "pendulum.yaml", "andrews-squeezer.yaml", "triple-crank.yaml",
         "wiper-drive.yaml", "knuckle-press.yaml"]  # (the last two written by hand: checked only)


def check_all():
    try:
        import yaml  # noqa: F401
    except ImportError:
        print("PyYAML not installed: check skipped")
        return True
    ok = True
    for fname in FILES:
        r = check_file(os.path.join(OUT, fname))
        good = r["resid"] < 1e-12 and r["dof"] == 1
        ok &= good
        print(f"{fname:26s} n={r['n']:3d} nc={r['nc']:3d} grubler={r['grubler']:2d} rank={r['rank']:3d} "
              f"dof={r['dof']} max|f| (file units)={r['resid']:.1e} {'ok' if good else 'FAIL'}")
    # change points: triple crank and N-four-bar at the horizontal position
    def horizontal_triple(q):
        q = list(q)
        for k in range(3):
            q[3 * k + 2] = 0.0
        q[9], q[10], q[11] = 0.05, 0.0, 0.0
        return q
    r = check_file(os.path.join(OUT, "stiff-spring-damper.yaml"))
    good = r["resid"] < 1e-12 and r["dof"] == 2
    ok &= good
    print(f"{'stiff-spring-damper.yaml':26s} n={r['n']:3d} nc={r['nc']:3d} grubler={r['grubler']:2d} "
          f"rank={r['rank']:3d} dof={r['dof']} max|f| (file units)={r['resid']:.1e} {'ok' if good else 'FAIL'}")
    r = check_file(os.path.join(OUT, "triple-crank.yaml"), horizontal_triple)
    print(f"  triple-crank at crank 0 deg: rank={r['rank']} dof={r['dof']} max|f|={r['resid']:.1e}")
    for N in (2,):
        def horizontal_n(q, N=N):
            q = list(q)
            for k in range(N + 1):
                q[3 * k + 2] = 0.0
            for k in range(N):
                o = 3 * (N + 1) + 3 * k
                q[o], q[o + 1], q[o + 2] = k + 1.0, 0.0, 0.0
            return q
        r = check_file(os.path.join(OUT, f"n-four-bar-{N}.yaml"), horizontal_n)
        print(f"  n-four-bar-{N} horizontal: rank={r['rank']} dof={r['dof']} max|f|={r['resid']:.1e}")
    return ok


def main():
    if "--check" not in sys.argv:
        os.makedirs(OUT, exist_ok=True)
        info = {}
        info["crank-rocker"] = gen_crank_rocker()
        info["double-rocker"] = gen_double_rocker()
        info["slider-crank"] = gen_slider_crank()
        info["watt"] = gen_watt()
        info["stephenson"] = gen_stephenson()
        info["quick-return"] = gen_quick_return()
        info["n2"] = gen_n_four_bar(2)
        info["n40"] = gen_n_four_bar(40)
        gen_pendulum()
        info["stiff"] = gen_stiff_spring_damper()
        info["andrews"] = gen_andrews()
        gen_triple_crank()
        for k, v in info.items():
            print(k, v)
    sys.exit(0 if check_all() else 1)


if __name__ == "__main__":
    main()
