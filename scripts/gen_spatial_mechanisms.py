#!/usr/bin/env python3
"""Generate the bundled spatial mechanism files (dimension: 3) in mechanisms/ (standard library).

    python3 scripts/gen_spatial_mechanisms.py

Writes bennett.yaml, bricard.yaml, hooke-joint.yaml, spatial-slider-crank.yaml, heavy-top.yaml,
rolling-disc.yaml, crank-rocker-3d.yaml and double-wishbone.yaml from the geometry of /work/shared/spatial.md §4 (and,
for crank-rocker-3d, the planar mechanisms/crank-rocker.yaml), and the test fixture
tests/data/spatial/double-wishbone-parallelogram.yaml. Design poses are computed here in closed
form and printed at full double precision (repr), so every joint holds at the design pose to ~1e-15 m;
the numbers quoted in each file's comment block are computed here too. rssr.yaml is the example
of spatial.md §5, written by hand (8-digit orientation axes).
"""
import math
import os

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "mechanisms")
DEG = math.pi / 180.0


# ---- small 3D algebra (tuples; matrices as tuples of rows) ------------------------------------
def add(a, b):
    return tuple(x + y for x, y in zip(a, b))


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def mul(s, a):
    return tuple(s * x for x in a)


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def norm(a):
    return math.sqrt(dot(a, a))


def unit(a):
    return mul(1.0 / norm(a), a)


def mat_mul(A, B):
    return tuple(tuple(sum(A[i][k] * B[k][j] for k in range(3)) for j in range(3)) for i in range(3))


def mat_vec(A, v):
    return tuple(dot(A[i], v) for i in range(3))


def col(A, j):
    return tuple(A[i][j] for i in range(3))


def rot_x(t):
    c, s = math.cos(t), math.sin(t)
    return ((1, 0, 0), (0, c, -s), (0, s, c))


def rot_z(t):
    c, s = math.cos(t), math.sin(t)
    return ((c, -s, 0), (s, c, 0), (0, 0, 1))


IDENTITY = ((1, 0, 0), (0, 1, 0), (0, 0, 1))


def v(a):
    """A vector as a YAML flow list at full precision (integers printed plainly)."""
    return "[" + ", ".join(num(x) for x in a) + "]"


def num(x):
    x = float(x)
    if abs(x) < 1e-15:  # round-off of an exact zero (sin π, the Bennett loop's closure)
        return "0"
    if x == int(x) and abs(x) < 1e15:
        return str(int(x))
    return repr(x)


def write(name, text, folder="mechanisms"):
    path = os.path.join(ROOT, folder)
    os.makedirs(path, exist_ok=True)
    with open(os.path.join(path, name), "w", encoding="utf-8") as f:
        f.write(text)
    print(f"wrote {folder}/{name}")


def rod_inertia(m, length, axis, radius=0.01):
    """Uniform slender rod along body axis `axis` (0, 1, 2): m L²/12 across, m r²/2 along."""
    J = [m * length * length / 12.0] * 3
    J[axis] = m * radius * radius / 2.0
    return J


# ---- Bennett 4R (spatial.md §4.2) ----------------------------------------------------------------
def bennett():
    a, alpha, beta = 0.3, 30 * DEG, 60 * DEG
    b = a * math.sin(beta) / math.sin(alpha)
    K = math.sin((beta + alpha) / 2) / math.sin((beta - alpha) / 2)
    th1 = 75 * DEG
    th2 = 2 * math.atan(K / math.tan(th1 / 2))
    th = [th1, th2, -th1, -th2]
    links = [(a, alpha), (b, beta), (a, alpha), (b, beta)]
    M = IDENTITY
    p = (0.0, 0.0, 0.0)
    frames = []  # (origin, rotation) of link k = 1..4 (after Rz(θ_k))
    for k in range(4):
        R = mat_mul(M, rot_z(th[k]))
        frames.append((p, R))
        p = add(p, mul(links[k][0], col(R, 0)))
        M = mat_mul(R, rot_x(links[k][1]))
    closure = max(norm(p), max(abs(M[i][j] - IDENTITY[i][j]) for i in range(3) for j in range(3)))
    assert closure < 1e-14, closure
    J4, R4 = frames[3]
    z4 = col(R4, 2)
    body = ""
    for k in range(3):
        o, R = frames[k]
        L = links[k][0]
        body += f"""  - name: link{k + 1}
    mass: 1
    inertia: {v(rod_inertia(1.0, L, 0))}
    com: {v((L / 2, 0, 0))}
    pose:
      position: {v(o)}
      orientation: {{x: {v(col(R, 0))}, z: {v(col(R, 2))}}}
    points: {{J{k + 1}: [0, 0, 0], J{k + 2}: {v((L, 0, 0))}}}
"""
    sa, ca = math.sin(alpha), math.cos(alpha)
    sb, cb = math.sin(beta), math.cos(beta)
    text = f"""# bennett.yaml — Bennett 4R linkage: the overconstrained spatial four-bar (dimension: 3).
#
# Source: spatial.md §4.2 (DH chain, all twists positive). T = Π Rz(θ_i)·Tx(a_i)·Rx(α_i) over
#   (a_i, α_i) = (a, α), (b, β), (a, α), (b, β) with a = 0.3 m, α = 30°, β = 60°,
#   b = a sin β / sin α = {b!r} m (Bennett's condition a/sin α = b/sin β).
#   Closure: θ3 = −θ1, θ4 = −θ2, tan(θ1/2) tan(θ2/2) = sin((β+α)/2)/sin((β−α)/2) = {K!r}.
#   Link k's frame: origin at joint k, z its axis, x along the common normal to joint k + 1; the
#   ground is link 4 (joints J1 at the origin, axis z, and J4). Links: 1 kg slender rods, com
#   mid-length, J = m L²/12 across and m r²/2 (r = 10 mm) along.
# Design pose: θ1 = 75°, θ2 = {th2 / DEG!r}° (closure of the DH loop {closure:.1e}),
#   computed by scripts/gen_spatial_mechanisms.py.
# Facts tests rely on:
#   - 3 moving bodies, 4 revolutes: n = 18, n_c = 20, Grübler −2; rank 17: DOF 1, 3 redundant.
#   - θ1 = 20°, 75°, 140° → θ2 = 172.6144863489°, 148.6240189537°, 89.6773892272°
#     (measures theta1, theta2 read θ1 and θ2).
#   - design_positions t20, t75, t140 (J1 at those θ1): `validate` passes, DOF 1 and 3 redundant
#     equations at each, one circuit with no dead point of J1 (θ1 turns fully).
orthomech: 1
dimension: 3
name: bennett
description: "Bennett 4R linkage, a = 0.3 m, alpha = 30 deg, beta = 60 deg"
units: {{length: m, angle: deg, mass: kg, time: s, force: N}}
ground:
  points: {{J1: [0, 0, 0], J4: {v(J4)}}}
bodies:
{body}joints:
  - {{name: J1, type: revolute, connects: [ground.J1, link1.J1], axis: [0, 0, 1]}}
  - {{name: J2, type: revolute, connects: [link1.J2, link2.J2], axis: {v((0, -sa, ca))}}}
  - {{name: J3, type: revolute, connects: [link2.J3, link3.J3], axis: {v((0, -sb, cb))}}}
  - {{name: J4, type: revolute, connects: [link3.J4, ground.J4], axis: {v((0, -sa, ca))}}}
loads:
  - {{name: weight, type: gravity}}
measures:
  - {{name: theta1, type: joint, joint: J1}}
  - {{name: theta2, type: joint, joint: J2}}
drivers:
  - {{name: motor, joint: J1, speed: 60 rpm}}
design_positions:
  - {{name: t20, inputs: {{J1: 20}}}}
  - {{name: t75, inputs: {{J1: 75}}}}
  - {{name: t140, inputs: {{J1: 140}}}}
analysis: {{driver: motor, steps: 360}}
"""
    write("bennett.yaml", text)


# ---- Bricard 6R (spatial.md §4.3) ----------------------------------------------------------------
def bricard():
    J = [(0, 0, 0), (1, 0, 0), (1, -1, 0), (1, -1, 1), (0, -1, 1), (0, 0, 1)]
    axes = ["[0, 1, 0]", "[0, 0, 1]", "[1, 0, 0]", "[0, 1, 0]", "[0, 0, 1]", "[1, 0, 0]"]
    body = ""
    for k in range(5):
        d = sub(J[k + 1], J[k])
        along = [i for i in range(3) if d[i] != 0][0]
        body += f"""  - name: rod{k + 1}
    mass: 1
    inertia: {v(rod_inertia(1.0, 1.0, along))}
    com: {v(mul(0.5, d))}
    pose: {{position: {v(J[k])}}}
    points: {{J{k + 1}: [0, 0, 0], J{k + 2}: {v(d)}}}
"""
    joints = ""
    for k in range(6):
        first = "ground.J1" if k == 0 else f"rod{k}.J{k + 1}"
        second = f"rod{k + 1}.J{k + 1}" if k < 5 else "ground.J6"
        joints += (f"  - {{name: J{k + 1}, type: revolute, connects: [{first}, {second}], "
                   f"axis: {axes[k]}}}\n")
    text = f"""# bricard.yaml — Bricard 6R linkage (IFToMM A04 geometry; dimension: 3).
#
# Source: spatial.md §4.3. Joints (m) and axes: J1 (0,0,0) y; J2 (1,0,0) z; J3 (1,−1,0) x;
#   J4 (1,−1,1) y; J5 (0,−1,1) z; J6 (0,0,1) x. Rods of 1 m and 1 kg between consecutive joints;
#   the ground is the rod J6–J1 (assumed, spatial.md: not verified against the A04 files). Body
#   frames parallel to the world at the design pose, origin at the rod's first joint; slender rods,
#   J = m L²/12 across and m r²/2 (r = 10 mm) along. Gravity −y (A04).
# Facts tests rely on:
#   - 5 moving bodies, 6 revolutes: n = 30, n_c = 30, Grübler 0; rank 29: DOF 1, 1 redundant.
#   - The design pose is the drawn one (every joint holds exactly).
orthomech: 1
dimension: 3
name: bricard
description: "Bricard 6R linkage, IFToMM A04 geometry, 1 m rods"
units: {{length: m, angle: deg, mass: kg, time: s, force: N}}
ground:
  points: {{J1: [0, 0, 0], J6: [0, 0, 1]}}
bodies:
{body}joints:
{joints}loads:
  - {{name: weight, type: gravity, g: [0, -9.81, 0]}}
measures:
  - {{name: theta1, type: joint, joint: J1}}
  - {{name: J4_x, type: point, point: rod3.J4, component: x}}
  - {{name: J4_y, type: point, point: rod3.J4, component: y}}
  - {{name: J4_z, type: point, point: rod3.J4, component: z}}
"""
    write("bricard.yaml", text)


# ---- Hooke's joint (spatial.md §4.5) -------------------------------------------------------------
def hooke():
    beta = 30 * DEG
    L = 0.2
    a2 = (math.sin(beta), 0.0, math.cos(beta))
    pin2 = (math.cos(beta), 0.0, -math.sin(beta))  # ⟂ a2 and ⟂ pin 1 = y, in the shafts' plane
    o2 = mul(-L, a2)  # shaft 2's frame origin: L before the joint centre along −a2
    text = f"""# hooke-joint.yaml — Hooke's (Cardan) joint between two shafts at 30° (dimension: 3).
#
# Source: spatial.md §4.5. Shaft 1 on a revolute about world z, shaft 2 on a revolute about
#   a2 = (sin β, 0, cos β), β = 30°, both axes through the U-joint centre at the origin. Pin 1
#   (on shaft 1) = y, perpendicular to the plane of the shafts at θ1 = 0; pin 2 (on shaft 2) =
#   y × a2 = {v(pin2)} in world (in the plane of the shafts), the shaft 2 frame's x. Shafts: 1 kg slender rods of
#   {L} m ending at the joint centre (frame origin at the far end, z along the shaft).
#   The revolute of shaft 2 takes `ref: pin 2` on the ground side so that θ2 = 0 at θ1 = 0.
# Closed form: tan θ2 = cos β tan θ1 (θ1, θ2 the joint measures), so ω2/ω1 = cos β / (1 − sin²β
#   sin²θ1). (spatial.md §4.5 writes tan θ2 = tan θ1 / cos β: the same motion with the roles of
#   the shafts exchanged; its ratio formula is the one here.)
#   Extremes cos β = 0.866025403784 at θ1 = 0 and 1/cos β = 1.154700538379 at θ1 = 90°.
# Facts tests rely on:
#   - 2 moving bodies, 2 revolutes and a universal joint: n = 12, n_c = 5 + 5 + 4 = 14,
#     Grübler −2; rank 11: DOF 1, 3 redundant (the revolute axes meet at the U-joint centre).
#   - design_positions t0, t45, t90 (R1 at those θ1): `validate` passes, DOF 1, 3 redundant.
orthomech: 1
dimension: 3
name: hooke-joint
description: "Hooke's joint, shafts at 30 deg"
units: {{length: m, angle: deg, mass: kg, time: s, force: N}}
ground:
  points: {{O: [0, 0, 0]}}
bodies:
  - name: shaft1
    mass: 1
    inertia: {v(rod_inertia(1.0, L, 2))}
    com: {v((0, 0, L / 2))}
    pose: {{position: {v((0, 0, -L))}}}
    points: {{E: [0, 0, 0], C: {v((0, 0, L))}}}
  - name: shaft2
    mass: 1
    inertia: {v(rod_inertia(1.0, L, 2))}
    com: {v((0, 0, L / 2))}
    pose:
      position: {v(o2)}
      orientation: {{z: {v(a2)}, x: {v(pin2)}}}
    points: {{E: [0, 0, 0], C: {v((0, 0, L))}}}
joints:
  - {{name: R1, type: revolute, connects: [ground.O, shaft1.C], axis: [0, 0, 1]}}
  - {{name: R2, type: revolute, connects: [ground.O, shaft2.C], axis: {v(a2)}, ref: {v(pin2)}}}
  - {{name: U, type: universal, connects: [shaft1.C, shaft2.C], axes: [[0, 1, 0], [1, 0, 0]]}}
measures:
  - {{name: theta1, type: joint, joint: R1}}
  - {{name: theta2, type: joint, joint: R2}}
  - {{name: omega2, type: joint, joint: R2, derivative: 1}}
drivers:
  - {{name: motor, joint: R1, speed: 60 rpm}}
design_positions:
  - {{name: t0, inputs: {{R1: 0}}}}
  - {{name: t45, inputs: {{R1: 45}}}}
  - {{name: t90, inputs: {{R1: 90}}}}
analysis: {{driver: motor, steps: 360}}
"""
    write("hooke-joint.yaml", text)


# ---- spatial slider-crank (spatial.md §4.4) --------------------------------------------------
def slider_crank():
    A0 = (0.0, 0.1, 0.12)
    r, l = 0.08, 0.3
    phi = 90 * DEG
    B = add(A0, mul(r, (0, math.cos(phi), math.sin(phi))))
    xc = math.sqrt(l * l - (0.1 + r * math.cos(phi)) ** 2 - (0.12 + r * math.sin(phi)) ** 2)
    C = (xc, 0.0, 0.0)
    d = unit(sub(C, B))
    pin2 = unit(cross((0, 0, 1), d))
    crank_x = (0.0, math.cos(phi), math.sin(phi))
    rate = 6.0
    xdot = (B[1] * r * math.sin(phi) - B[2] * r * math.cos(phi)) * rate / xc
    text = f"""# spatial-slider-crank.yaml — spatial slider-crank (IFToMM data; dimension: 3).
#
# Source: spatial.md §4.4. Crank 0.08 m, 0.12 kg, about world x through A0 = (0, 0.1, 0.12) m;
#   rod B–C 0.3 m, 0.5 kg; slider 2 kg on the world x axis. Spherical joint at the crank end B,
#   universal joint at C (pin 1 = z on the slider, pin 2 on the rod ⟂ pin 1 and the rod: the rod
#   frame's y), prismatic slider–ground along x. Crank and rod: slender rods (J = m L²/12 across,
#   m r²/2 along, r = 10 mm); slider: a 2 kg block with J = diag(0.002, 0.004, 0.004) kg m²
#   (assumed: spatial.md says the benchmark's inertias and pin directions are not verified; they
#   change the dynamics, not the kinematics (M2)).
# Closed form (M2): B = A0 + 0.08 (0, cos φ, sin φ), x_C = √(0.09 − (0.1 + 0.08 cos φ)² −
#   (0.12 + 0.08 sin φ)²), ẋ_C = (B_y 0.08 sin φ − B_z 0.08 cos φ) φ̇ / x_C.
# Design pose: φ = 90° (crank along +z): B = {v(B)}, x_C = {xc!r} m. Initial crank rate
#   φ̇ = 6 rad/s about +x (`initial`), so ẋ_C = {xdot!r} m/s (the brief's initial conditions).
# Facts tests rely on:
#   - 3 moving bodies: n = 18, n_c = 5 + 3 + 4 + 5 = 17, Grübler 1, rank 17: DOF 1, no redundancy.
#   - Measures crank_angle (φ, from world y about x: 90° at the design pose), slider_x (the
#     prismatic slide = x_C), slider_v.
#   - design_positions p90, p135, p180 (A0 at those φ): `validate` passes, x_C = (M2) there.
orthomech: 1
dimension: 3
name: spatial-slider-crank
description: "Spatial slider-crank: crank about x, spherical and universal rod ends, slider on x"
units: {{length: m, angle: deg, mass: kg, time: s, force: N}}
ground:
  points: {{A0: {v(A0)}, O: [0, 0, 0]}}
bodies:
  - name: crank
    mass: 0.12
    inertia: {v(rod_inertia(0.12, r, 0))}
    com: {v((r / 2, 0, 0))}
    pose:
      position: {v(A0)}
      orientation: {{x: {v(crank_x)}, z: [1, 0, 0]}}
    points: {{O: [0, 0, 0], B: {v((r, 0, 0))}}}
  - name: rod
    mass: 0.5
    inertia: {v(rod_inertia(0.5, l, 0))}
    com: {v((l / 2, 0, 0))}
    pose:
      position: {v(B)}
      orientation: {{x: {v(d)}, y: {v(pin2)}}}
    points: {{B: [0, 0, 0], C: {v((l, 0, 0))}}}
  - name: slider
    mass: 2
    inertia: [0.002, 0.004, 0.004]
    pose: {{position: {v(C)}}}
    points: {{C: [0, 0, 0]}}
joints:
  - {{name: A0, type: revolute, connects: [ground.A0, crank.O], axis: [1, 0, 0]}}
  - {{name: B, type: spherical, connects: [crank.B, rod.B]}}
  - {{name: C, type: universal, connects: [slider.C, rod.C], axes: [[0, 0, 1], [0, 1, 0]]}}
  - {{name: slide, type: prismatic, connects: [ground.O, slider.C], axis: [1, 0, 0]}}
loads:
  - {{name: weight, type: gravity}}
measures:
  - {{name: crank_angle, type: joint, joint: A0}}
  - {{name: slider_x, type: joint, joint: slide}}
  - {{name: slider_v, type: joint, joint: slide, derivative: 1}}
drivers:
  - {{name: motor, joint: A0, speed: 6 rad/s}}
initial:
  rates: {{crank_angle: 6 rad/s}}
design_positions:
  - {{name: p90, inputs: {{A0: 90}}}}
  - {{name: p135, inputs: {{A0: 135}}}}
  - {{name: p180, inputs: {{A0: 180}}}}
analysis: {{driver: motor, steps: 360}}
"""
    write("spatial-slider-crank.yaml", text)


# ---- heavy symmetric top (spatial.md §4.6) ----------------------------------------------------
def heavy_top():
    m, l, A_cm, C = 1.0, 0.1, 0.002, 0.004
    A_O = A_cm + m * l * l
    g = 9.81
    theta = 30 * DEG
    w3 = 100.0
    disc = C * C * w3 * w3 - 4 * A_O * m * g * l * math.cos(theta)
    slow = (C * w3 - math.sqrt(disc)) / (2 * A_O * math.cos(theta))
    fast = (C * w3 + math.sqrt(disc)) / (2 * A_O * math.cos(theta))
    a = (math.sin(theta), 0.0, math.cos(theta))
    bx = (math.cos(theta), 0.0, -math.sin(theta))
    w = add(mul(slow, (0, 0, 1)), mul(w3 - slow * math.cos(theta), a))
    com = mul(l, a)
    P = add(mul(0.05, bx), mul(l, a))
    Q = add(mul(0.05, (0, 1, 0)), mul(l, a))  # body y = world y at the design pose
    v_com = cross(w, com)
    v_P = cross(w, P)
    v_Q = cross(w, Q)
    text = f"""# heavy-top.yaml — heavy symmetric top on a spherical joint (dimension: 3).
#
# Source: spatial.md §4.6. m = 1 kg, centre of mass l = 0.1 m from the fixed tip along the
#   symmetry axis (body z), A_cm = 0.002, C = 0.004 kg m² (A_O = A_cm + m l² = 0.012); the tip is
#   a spherical joint to the ground at the origin; g = 9.81 m/s² along −z.
# Steady precession (M3): Ω (C ω3 − A_O Ω cos θ) = m g l. At nutation θ = 30° (axis
#   (sin θ, 0, cos θ), the pose below) and spin ω3 = w·axis = 100 rad/s:
#   Ω_slow = {slow!r} rad/s, Ω_fast = {fast!r} rad/s.
# Initial state (slow precession): w = Ω z + (ω3 − Ω cos θ) axis = {v(w)} rad/s (world).
#   `initial` gives it as three measure rates that fix w (the top has 3 rotational DOF): com_y
#   (v = w × l axis), P_y and Q_x (P, Q = 0.05 m along body x, y from the axis at the com's
#   height; P_y carries the spin, Q_x the w_y component): v_com = {v(v_com)},
#   v_P = {v(v_P)}, v_Q = {v(v_Q)} m/s. (Rates must be non-zero in `initial`, so
#   com_x, whose rate is 0, cannot be given: these three determine w, det ≠ 0.)
# Facts tests rely on:
#   - 1 moving body, 1 spherical joint: n = 6, n_c = 3, rank 3: DOF 3, no redundancy.
#   - Under `simulate` from `initial`: θ stays 30°, the axis precesses at Ω_slow about z.
orthomech: 1
dimension: 3
name: heavy-top
description: "Heavy symmetric top, l = 0.1 m, A = 0.002, C = 0.004 kg m2, nutation 30 deg"
units: {{length: m, angle: deg, mass: kg, time: s, force: N}}
ground:
  points: {{O: [0, 0, 0]}}
bodies:
  - name: top
    mass: 1
    inertia: [0.002, 0.002, 0.004]
    com: [0, 0, 0.1]
    pose: {{position: [0, 0, 0], orientation: {{axis: [0, 1, 0], angle: 30}}}}
    points: {{tip: [0, 0, 0], C: [0, 0, 0.1], P: [0.05, 0, 0.1], Q: [0, 0.05, 0.1]}}
joints:
  - {{name: tip, type: spherical, connects: [ground.O, top.tip]}}
loads:
  - {{name: weight, type: gravity, g: [0, 0, -9.81]}}
measures:
  - {{name: com_x, type: point, point: top.C, component: x}}
  - {{name: com_y, type: point, point: top.C, component: y}}
  - {{name: com_z, type: point, point: top.C, component: z}}
  - {{name: P_y, type: point, point: top.P, component: y}}
  - {{name: Q_x, type: point, point: top.Q, component: x}}
  - {{name: nutation, type: angle, between: [{{body: top, vector: [0, 0, 1]}}, {{body: ground, vector: [0, 0, 1]}}]}}
initial:
  rates: {{com_y: {num(v_com[1])}, P_y: {num(v_P[1])}, Q_x: {num(v_Q[0])}}}
"""
    write("heavy-top.yaml", text)


# ---- rolling disc, steady circular rolling (spatial.md §3.1) -----------------------------------
def rolling_disc():
    rho, m, A, Cs, g = 0.1, 1.0, 0.0025, 0.005, 9.81
    theta, Om = 20 * DEG, 3.0
    s, c = math.sin(theta), math.cos(theta)
    s_r = (A * Om * Om * s * c - m * g * rho * s) / ((Cs + m * rho * rho) * Om * c)  # (D1)
    V = rho * s_r
    R_c = V / Om
    sigma = s_r - Om * s
    a = (0.0, c, s)
    e1 = (1.0, 0.0, 0.0)
    by = cross(a, e1)  # body y: from the centre towards the contact point
    r_C = mul(rho, (0.0, -s, c))
    w = add(mul(Om, (0, 0, 1)), mul(sigma, a))
    omega = (dot(e1, w), dot(by, w), dot(a, w))  # body frame
    vel = (V, 0.0, 0.0)
    v_F = add(vel, cross(w, mul(rho, e1)))   # front rim point F = C + ρ e1
    v_B = add(vel, cross(w, mul(-rho, e1)))  # back rim point B = C − ρ e1
    F_friction = m * Om * V  # along e2 = the horizontal projection of the axis, (0, 1, 0) at t = 0
    text = f"""# rolling-disc.yaml — a thin disc rolling without slipping on the plane z = 0 (dimension: 3).
#
# Source: spatial.md §3 (rows (D0)) and §3.1 (steady circular rolling (D1)). Thin uniform disc:
#   radius ρ = 0.1 m, m = 1 kg, A = m ρ²/4 = 0.0025 (diametral), C_s = m ρ²/2 = 0.005 kg m² (axial,
#   body z); gravity g = 9.81 m/s² along −z. `nonholonomic:` rolling-disc `contact`: rows t1, t2
#   (no slip, nonholonomic) and n (contact, holonomic: the lowest rim point on the plane).
# Steady motion (D1): A Ω² sin θ cos θ − (C_s + m ρ²) Ω s_r cos θ = m g ρ sin θ, θ the tilt of the
#   axis above the horizontal, Ω the precession rate about z, s_r = w·a the spin. Here θ = 20°,
#   Ω = 3 rad/s: s_r = {s_r!r} rad/s, σ = s_r − Ω sin θ = {sigma!r} rad/s,
#   V = ρ s_r = {V!r} m/s (speed of the centre), R_c = V/Ω = {R_c!r} m (radius of the
#   centre's circle; negative: its centre lies on the −e2 side, toward which the disc leans).
# Initial state: contact at the origin, heading e1 = x, axis a = (0, cos θ, sin θ) (the pose below:
#   body x = e1, body z = a, body y = a × e1 points from the centre to the contact point),
#   r_C = ρ (0, −sin θ, cos θ); v = (V, 0, 0), w = Ω z + σ a = {v(w)} rad/s (world),
#   ω = {v(omega)} rad/s (body).
#   `initial` gives it as three measure rates that fix the admissible velocity (3 of the 6 are
#   free: w; v = ρ_P × w): C_x = V, F_z and B_z (the front and back rim points F, B = C ± ρ e1):
#   v_F = {v(v_F)}, v_B = {v(v_B)} m/s. (Rates must be non-zero in `initial`; these three
#   determine w, det = −2 ρ³ sin² θ ≠ 0.)
# Facts tests rely on:
#   - 1 moving body, 1 rolling disc: n = 6, n_c = 3 (t1, t2 nonholonomic, n holonomic), rank 3:
#     3 velocity DOF (5 position DOF).
#   - Under `simulate` from `initial`: tilt 20° (measure `tilt` = 70°, the axis from the vertical)
#     constant, the centre on a circle of radius |R_c| about r_C,xy(0) + R_c e2 = (0, {num(-rho * s + R_c)}),
#     heading Ω t, w·a = s_r; energy conserved.
#   - Contact force (spatial.md §3.1): F = m Ω V e2 + m g z: normal force `contact.N` = m g = 9.81 N,
#     friction {num(F_friction)} N along e2 (the horizontal projection of the axis; toward the centre
#     of the circle), `contact.Fz` = 9.81 N.
orthomech: 1
dimension: 3
name: rolling-disc
description: "Thin disc rho = 0.1 m, m = 1 kg rolling on z = 0: steady circular rolling, tilt 20 deg, precession 3 rad/s"
units: {{length: m, angle: deg, mass: kg, time: s, force: N}}
bodies:
  - name: disc
    mass: 1
    inertia: [0.0025, 0.0025, 0.005]
    pose: {{position: {v(r_C)}, orientation: {{x: [1, 0, 0], z: {v(a)}}}}}
    points: {{C: [0, 0, 0], F: [0.1, 0, 0], B: [-0.1, 0, 0]}}
nonholonomic:
  - {{name: contact, type: rolling-disc, body: disc, radius: 0.1, axis: [0, 0, 1],
     plane: {{point: [0, 0, 0], normal: [0, 0, 1]}}, t1: [1, 0, 0]}}
loads:
  - {{name: weight, type: gravity, g: [0, 0, -9.81]}}
measures:
  - {{name: C_x, type: point, point: disc.C, component: x}}
  - {{name: C_y, type: point, point: disc.C, component: y}}
  - {{name: C_z, type: point, point: disc.C, component: z}}
  - {{name: F_z, type: point, point: disc.F, component: z}}
  - {{name: B_z, type: point, point: disc.B, component: z}}
  - {{name: tilt, type: angle, between: [{{body: disc, vector: [0, 0, 1]}}, {{body: ground, vector: [0, 0, 1]}}]}}
initial:
  rates: {{C_x: {num(V)}, F_z: {num(v_F[2])}, B_z: {num(v_B[2])}}}
"""
    write("rolling-disc.yaml", text)


# ---- crank-rocker rebuilt with spatial bodies --------------------------------------------------
def crank_rocker_3d():
    # The planar file's numbers (mechanisms/crank-rocker.yaml, from scripts/gen_mechanisms.py).
    bodies = [
        ("crank", 0.03, 2.25, 30.0, (0.0, 0.0, 60.0), {"A0": (0, 0), "A": (30, 0)}),
        ("coupler", 0.08, 42.6666666666667, 80.0,
         (15.000000000000004, 25.980762113533157, 22.812053275345825),
         {"A": (0, 0), "B": (80, 0), "P": (40, 20)}),
        ("rocker", 0.06, 18.0, 60.0, (70.0, 0.0, 71.79755360961532), {"B0": (0, 0), "B": (60, 0)}),
    ]
    text_bodies = ""
    for name, m, J, L, pose, pts in bodies:
        axial = m * 3.0 ** 2 / 2.0  # a rod of radius 3 mm, kg mm²
        points = ", ".join(f"{k}: [{num(p[0])}, {num(p[1])}, 0]" for k, p in pts.items())
        text_bodies += f"""  - name: {name}
    mass: {num(m)}
    inertia: [{num(axial)}, {num(J)}, {num(J)}]
    com: [{num(L / 2)}, 0, 0]
    pose:
      position: [{num(pose[0])}, {num(pose[1])}, 0]
      orientation: {{axis: [0, 0, 1], angle: {num(pose[2])}}}
    points: {{{points}}}
"""
    text = f"""# crank-rocker-3d.yaml — mechanisms/crank-rocker.yaml rebuilt with spatial bodies (dimension: 3).
#
# Source: the planar crank-rocker (ground 70, crank 30, coupler 80, rocker 60 mm; its numbers,
#   poses and masses copied from mechanisms/crank-rocker.yaml), every body a spatial body in the
#   plane z = 0 turned about z by its planar angle, every joint a spatial revolute about z.
#   Inertia about z as planar (m L²/12); about x m r²/2 (r = 3 mm), about y as about z.
# Facts tests rely on:
#   - 3 moving bodies, 4 revolutes: n = 18, n_c = 20, Grübler −2; rank 17: DOF 1, 3 redundant
#     (the planar loop's out-of-plane rows repeat each other).
#   - The motion is the planar one: crank_angle 60° at the design pose, rocker_angle
#     71.79755360961532°; rocker limit positions as in crank-rocker.yaml.
orthomech: 1
dimension: 3
name: crank-rocker-3d
description: "Grashof crank-rocker four-bar (30/80/60 mm on a 70 mm ground) with spatial bodies"
units: {{length: mm, angle: deg, mass: kg, time: s, force: N}}
ground:
  points: {{A0: [0, 0, 0], B0: [70, 0, 0]}}
bodies:
{text_bodies}joints:
  - {{name: A0, type: revolute, connects: [ground.A0, crank.A0], axis: [0, 0, 1]}}
  - {{name: A, type: revolute, connects: [crank.A, coupler.A], axis: [0, 0, 1]}}
  - {{name: B, type: revolute, connects: [coupler.B, rocker.B], axis: [0, 0, 1]}}
  - {{name: B0, type: revolute, connects: [ground.B0, rocker.B0], axis: [0, 0, 1]}}
loads:
  - {{name: weight, type: gravity, g: [0, -9810, 0]}}   # mm/s², −y as the planar file
measures:
  - {{name: crank_angle, type: joint, joint: A0}}
  - {{name: rocker_angle, type: joint, joint: B0}}
  - {{name: P_x, type: point, point: coupler.P, component: x}}
  - {{name: P_y, type: point, point: coupler.P, component: y}}
drivers:
  - {{name: motor, joint: A0, speed: 300 rpm}}
design_positions:
  - {{name: p1, inputs: {{A0: 60}}}}
analysis: {{driver: motor, steps: 360}}
"""
    write("crank-rocker-3d.yaml", text)


# ---- double-wishbone suspension (spatial.md §4.8) ----------------------------------------------
def rodrigues(th, a):
    """exp(θ̃) a: rotation of a by |θ| about θ/|θ|."""
    t = norm(th)
    if t == 0.0:
        return a
    k = mul(1.0 / t, th)
    c, s = math.cos(t), math.sin(t)
    return add(add(mul(c, a), mul(s, cross(k, a))), mul(dot(k, a) * (1.0 - c), k))


def solve4(F, x):
    """Newton on F(x) = 0, x ∈ R⁴, central-difference Jacobian, Gaussian elimination."""
    for _ in range(50):
        f = F(x)
        if max(abs(r) for r in f) < 1e-15:
            break
        h = 1e-7
        A = [[0.0] * 5 for _ in range(4)]
        for k in range(4):
            xp, xm = list(x), list(x)
            xp[k] += h
            xm[k] -= h
            fp, fm = F(xp), F(xm)
            for i in range(4):
                A[i][k] = (fp[i] - fm[i]) / (2 * h)
        for i in range(4):
            A[i][4] = -f[i]
        for c in range(4):
            p = max(range(c, 4), key=lambda r: abs(A[r][c]))
            A[c], A[p] = A[p], A[c]
            for r in range(c + 1, 4):
                m = A[r][c] / A[c][c]
                for k in range(c, 5):
                    A[r][k] -= m * A[c][k]
        dx = [0.0] * 4
        for i in range(3, -1, -1):
            dx[i] = (A[i][4] - sum(A[i][k] * dx[k] for k in range(i + 1, 4))) / A[i][i]
        x = [a + b for a, b in zip(x, dx)]
    return x, max(abs(r) for r in F(x))


def wishbone_pose(G, psi, x0):
    """The loop at lower-arm angle ψ: unknowns the upper-arm angle β and the upright's rotation
    vector θ (from the design pose): LBJ(ψ) + R(θ)(UBJ − LBJ) = UBJ(β), |tie rod| = its length.
    Returns (x, camber, toe, wheel-centre z, residual)."""
    Ltr = norm(sub(G["TRo"], G["TRi"]))
    La, Ua = unit(sub(G["LAf"], G["LAr"])), unit(sub(G["UAf"], G["UAr"]))
    lbj = add(G["LAr"], rodrigues(mul(psi, La), sub(G["LBJ"], G["LAr"])))

    def F(x):
        ubj = add(G["UAr"], rodrigues(mul(x[0], Ua), sub(G["UBJ"], G["UAr"])))
        r = sub(add(lbj, rodrigues(x[1:], sub(G["UBJ"], G["LBJ"]))), ubj)
        t = sub(add(lbj, rodrigues(x[1:], sub(G["TRo"], G["LBJ"]))), G["TRi"])
        return list(r) + [(dot(t, t) - Ltr * Ltr) / (2 * Ltr)]

    x, res = solve4(F, x0)
    s = rodrigues(x[1:], (0.0, 1.0, 0.0))
    wc = add(lbj, rodrigues(x[1:], sub(G["WC"], G["LBJ"])))
    return x, -math.asin(s[2]), math.atan2(s[0], s[1]), wc[2], res


def wishbone_sweep(G, degrees):
    """Continuation from the design pose (ψ = 0) in 1° steps to each angle of `degrees`."""
    out = {}
    for sign in (1, -1):
        x = [0.0] * 4
        for d in range(0, max(abs(a) for a in degrees) + 1):
            x, camber, toe, z, res = wishbone_pose(G, sign * d * DEG, x)
            assert res < 1e-14, res
            if sign * d in degrees:
                out[sign * d] = (x[0], camber, toe, z)
    return out


WISHBONE = {  # spatial.md §4.8, m: x forward, y outboard (left wheel), z up
    "LAf": (0.15, 0.25, 0.15), "LAr": (-0.15, 0.25, 0.15), "LBJ": (0.0, 0.70, 0.12),
    "UAf": (0.12, 0.35, 0.45), "UAr": (-0.12, 0.35, 0.45), "UBJ": (0.0, 0.66, 0.42),
    "TRi": (-0.12, 0.28, 0.20), "TRo": (-0.12, 0.68, 0.18), "WC": (0.0, 0.75, 0.27),
}
# The exact special case (i) of §4.8: equal, parallel arms and a tie rod parallel to them.
WISHBONE_PARALLELOGRAM = dict(WISHBONE)
WISHBONE_PARALLELOGRAM.update({
    "UAf": add(WISHBONE["LAf"], (0, 0, 0.3)), "UAr": add(WISHBONE["LAr"], (0, 0, 0.3)),
    "UBJ": add(WISHBONE["LBJ"], (0, 0, 0.3)),
    "TRi": (-0.12, 0.25, 0.20), "TRo": add((-0.12, 0.25, 0.20), sub(WISHBONE["LBJ"], (0, 0.25, 0.15))),
})


def point_masses_inertia(m, pts, extra):
    """Inertia about the centroid of equal point masses m/len(pts) at pts, plus extra·m·I (so the
    principal moments satisfy the triangle inequality strictly). Returns (com, [Jxx..Jyz])."""
    c = mul(1.0 / len(pts), tuple(sum(p[i] for p in pts) for i in range(3)))
    J = [[0.0] * 3 for _ in range(3)]
    for p in pts:
        r = sub(p, c)
        for i in range(3):
            for j in range(3):
                J[i][j] += m / len(pts) * ((dot(r, r) if i == j else 0.0) - r[i] * r[j])
    for i in range(3):
        J[i][i] += extra * m
    return c, [J[0][0], J[1][1], J[2][2], J[0][1], J[0][2], J[1][2]]


def r12(a):
    """A vector rounded to 12 decimals (differences of the §4.8 points print as 0.45, not
    0.44999999999999996; the joints still hold to ~1e-16 m)."""
    return tuple(round(x, 12) for x in a)


def wishbone_text(G, name, title, header):
    L0 = mul(0.5, add(G["LAf"], G["LAr"]))
    U0 = mul(0.5, add(G["UAf"], G["UAr"]))
    bodies = ""
    for body, O, f, r, bj, m in (("lower_arm", L0, "LAf", "LAr", "LBJ", 3.0),
                                  ("upper_arm", U0, "UAf", "UAr", "UBJ", 2.0)):
        F, R, B = r12(sub(G[f], O)), r12(sub(G[r], O)), r12(sub(G[bj], O))
        com, J = point_masses_inertia(m, [F, R, B], 1e-3)
        com, J = r12(com), r12(J)
        bodies += f"""  - name: {body}
    mass: {num(m)}
    inertia: {v(J)}
    com: {v(com)}
    pose: {{position: {v(O)}}}
    points: {{O: [0, 0, 0], F: {v(F)}, R: {v(R)}, B: {v(B)}}}
"""
    W = G["WC"]
    bodies += f"""  - name: upright
    mass: 20
    inertia: [0.6, 1.0, 0.6]                 # upright, hub and wheel; spin axis = body y
    pose: {{position: {v(W)}}}
    points:
      W: [0, 0, 0]
      L: {v(r12(sub(G["LBJ"], W)))}
      U: {v(r12(sub(G["UBJ"], W)))}
      T: {v(r12(sub(G["TRo"], W)))}
"""
    return f"""{header}orthomech: 1
dimension: 3
name: {name}
description: "{title}"
units: {{length: m, angle: deg, mass: kg, time: s, force: N}}
ground:
  points: {{LA: {v(L0)}, UA: {v(U0)}, TR: {v(G["TRi"])}}}
bodies:
{bodies}joints:
  - {{name: LA, type: revolute, connects: [ground.LA, lower_arm.O], axis: {v(sub(G["LAf"], G["LAr"]))}}}
  - {{name: UA, type: revolute, connects: [ground.UA, upper_arm.O], axis: {v(sub(G["UAf"], G["UAr"]))}}}
  - {{name: LBJ, type: spherical, connects: [lower_arm.B, upright.L]}}
  - {{name: UBJ, type: spherical, connects: [upper_arm.B, upright.U]}}
  - {{name: tie_rod, type: distance, connects: [ground.TR, upright.T]}}
loads:
  - {{name: weight, type: gravity}}
measures:
  - {{name: psi, type: joint, joint: LA}}
  - {{name: upper_arm_angle, type: joint, joint: UA}}
  - {{name: camber, type: camber, body: upright, axis: [0, 1, 0]}}
  - {{name: toe, type: toe, body: upright, axis: [0, 1, 0]}}
  - {{name: wheel_z, type: point, point: upright.W, component: z}}
  - {{name: camber_rate, type: camber, body: upright, axis: [0, 1, 0], derivative: 1}}
  - {{name: toe_rate, type: toe, body: upright, axis: [0, 1, 0], derivative: 1}}
drivers:
  - {{name: travel, joint: LA, profile: harmonic, amplitude: 15, frequency: 1}}
analysis: {{driver: travel, steps: 360}}
"""


def double_wishbone():
    G = WISHBONE
    sweep = wishbone_sweep(G, [-15, -10, -5, 5, 10, 15])

    def row(d):
        beta, camber, toe, z = sweep[d]
        return (f"#     ψ = {d:+d}°: upper arm {beta / DEG:.10f}°, camber {camber / DEG:.10f}°, "
                f"toe {toe / DEG:.10f}°,\n#       wheel_z {z:.12f} m\n")

    rows = "".join(row(d) for d in (-15, -10, -5, 5, 10, 15))
    P = WISHBONE_PARALLELOGRAM
    psweep = wishbone_sweep(P, [-15, 15])
    pmax = max(max(abs(c), abs(t)) for _, c, t, _ in psweep.values())
    assert pmax < 1e-14, pmax
    fmt = lambda key: v(G[key])
    header = f"""# double-wishbone.yaml — double-wishbone front suspension, left wheel (dimension: 3).
#
# Source: spatial.md §4.8. Vehicle axes x forward, y outboard (left wheel), z up; m.
#   Lower arm: pivots LA_f = {fmt("LAf")}, LA_r = {fmt("LAr")},
#     ball joint LBJ = {fmt("LBJ")};
#   upper arm: pivots UA_f = {fmt("UAf")}, UA_r = {fmt("UAr")},
#     ball joint UBJ = {fmt("UBJ")};
#   tie rod: inner (chassis) {fmt("TRi")}, outer (upright) {fmt("TRo")};
#   wheel centre {fmt("WC")}, spin axis +y at the design pose. The chassis is the ground.
#   Arms on revolutes (axes LA_f − LA_r, UA_f − UA_r, through the pivots' mid-points), spherical
#   ball joints to the upright, the tie rod a `distance` row (massless rod, spherical ends). Masses and inertias are
#   assumed (arms: equal point masses at their three corners; upright with hub and wheel 20 kg,
#   com at the wheel centre); they change the dynamics, not the kinematics below.
# Input: the lower-arm angle ψ (joint LA, measure `psi`; > 0 moves the wheel up, bump).
# Measures (docs/file-format.md): camber = −asin(s_z) (> 0: top of the wheel outboard), toe =
#   atan2(s_x, s_y) (> 0: toe-in), s the spin axis; wheel_z = the wheel centre's height (travel).
# Facts tests rely on (tests/unit/analysis/positions_double_wishbone_test.cpp):
#   - 3 moving bodies: n = 18, n_c = 5 + 5 + 3 + 3 + 1 = 17, Grübler 1, rank 17: DOF 1.
#   - Design pose ψ = 0: camber 0, toe 0, wheel_z 0.27 m (every joint holds exactly).
#   - An independent loop solve (Newton in the upper-arm angle and the upright's rotation,
#     scripts/gen_spatial_mechanisms.py) gives, continued from the design pose:
{rows}#   - Equal, parallel arms with a parallel tie rod (UA = LA + (0, 0, 0.3), UBJ = LBJ + (0, 0, 0.3),
#     tie rod inner {v(P["TRi"])}, outer {v(r12(P["TRo"]))}): the upright translates,
#     camber and toe stay 0 over the travel (tests/data/spatial/double-wishbone-parallelogram.yaml).
"""
    write("double-wishbone.yaml", wishbone_text(
        G, "double-wishbone", "Double-wishbone front suspension, left wheel (spatial.md 4.8)", header))
    pheader = f"""# double-wishbone-parallelogram.yaml — test fixture: mechanisms/double-wishbone.yaml with
# equal, parallel arms and a tie rod parallel to them (spatial.md §4.8 (i); written by
# scripts/gen_spatial_mechanisms.py). UA = LA + (0, 0, 0.3), UBJ = LBJ + (0, 0, 0.3), tie rod
# inner {v(P["TRi"])}, outer {v(r12(P["TRo"]))} = inner + (LBJ − LA): the upright
# translates, camber and toe are 0 over the travel (the independent solve: max {pmax:.1e} rad
# over ψ = ±15°).
"""
    write("double-wishbone-parallelogram.yaml", wishbone_text(
        P, "double-wishbone-parallelogram", "Double wishbone with a parallelogram linkage",
        pheader), "tests/data/spatial")


def stewart():
    """Stewart platform (spatial.md §4.7): six U-P-S legs, each a cylinder and a piston."""
    base = [(math.cos(a * DEG), math.sin(a * DEG), 0.0) for a in (-15, 15, 105, 135, 225, 255)]
    plat = [(0.5 * math.cos(a * DEG), 0.5 * math.sin(a * DEG), 0.0)
            for a in (-45, 45, 75, 165, 195, 285)]
    home = (0.0, 0.0, 1.0)
    legs = []
    for i in range(6):
        top = add(home, plat[i])
        d = sub(top, base[i])
        n = unit(d)
        u = unit(cross((0.0, 0.0, 1.0), n))
        legs.append((norm(d), n, u, top))
    # IK of the reference pose of spatial.md §4.7, quoted in the header.
    c, s_ = math.cos, math.sin
    Rz, Ry, Rx = rot_z(10 * DEG), ((c(5 * DEG), 0, s_(5 * DEG)), (0, 1, 0), (-s_(5 * DEG), 0, c(5 * DEG))), rot_x(-5 * DEG)
    R = mat_mul(mat_mul(Rz, Ry), Rx)
    p = (0.1, -0.05, 1.1)
    ik = [norm(sub(add(p, mat_vec(R, plat[i])), base[i])) for i in range(6)]
    amplitudes = (0.04, -0.03, 0.05, 0.02, -0.045, 0.035)
    out = []
    out.append("""# stewart-platform.yaml — 6-6 Stewart platform with six U-P-S legs (dimension: 3).
#
# Source: spatial.md §4.7 (written by scripts/gen_spatial_mechanisms.py). Base radius 1.0 m,
#   joints at (-15, 15, 105, 135, 225, 255) deg in z = 0; platform radius 0.5 m, joints at
#   (-45, 45, 75, 165, 195, 285) deg in the platform's z = 0 plane; home pose p = (0, 0, 1) m,
#   R = I. Leg i: a cylinder on a universal joint at B_i (pins: the horizontal u_i ⟂ the leg,
#   and n_i × u_i), a piston on a prismatic joint along the leg (its slide = the leg length
#   l_i = |p + R P_i − B_i|), a spherical joint to the platform at P_i.
# Facts tests rely on:
#   - 13 moving bodies: n = 78, n_c = 6 (4 + 5 + 3) = 72, rank 72, DOF 6, no redundancy.
#   - Home leg lengths """ + ", ".join(f"{l:.12f}" for l, _, _, _ in legs) + """ m.
#   - IK at p = (0.1, -0.05, 1.1) m, R = Rz(10°) Ry(5°) Rx(-5°):
#     l = """ + ", ".join(f"{x:.12f}" for x in ik) + """ m.
#   - Drivers L1 … L6: harmonic leg lengths about the home lengths (amplitudes
#     """ + ", ".join(num(a) for a in amplitudes) + """ m, 0.5 Hz); `cycle --drivers L1,L2,L3,L4,L5,L6`
#     sweeps them over one period (2 s). The payload is a 981 N force at the platform's centre
#     (no gravity: the legs carry only the payload, so the leg forces are the Jacobian-transpose
#     equilibrium of the platform).
orthomech: 1
dimension: 3
name: stewart-platform
description: "6-6 Stewart platform, U-P-S legs, base radius 1 m, platform radius 0.5 m"
units: {length: m, angle: deg, mass: kg, time: s, force: N}
ground:
  points: {""" + ", ".join(f"B{i + 1}: {v(base[i])}" for i in range(6)) + """}
bodies:
  - name: platform
    mass: 20
    inertia: [1.25, 1.25, 2.5]
    com: [0, 0, 0]
    pose: {position: """ + v(home) + """, orientation: {axis: [0, 0, 1], angle: 0}}
    points: {C: [0, 0, 0], """ + ", ".join(f"P{i + 1}: {v(plat[i])}" for i in range(6)) + """}
""")
    for i, (l, n, u, top) in enumerate(legs):
        k = i + 1
        out.append(f"""  - name: cylinder{k}
    mass: 2
    inertia: [0.002, 0.06, 0.06]
    com: [0.3, 0, 0]
    pose: {{position: {v(base[i])}, orientation: {{x: {v(n)}, y: {v(u)}}}}}
    points: {{B: [0, 0, 0]}}
  - name: piston{k}
    mass: 1
    inertia: [0.001, 0.03, 0.03]
    com: [-0.3, 0, 0]
    pose: {{position: {v(top)}, orientation: {{x: {v(n)}, y: {v(u)}}}}}
    points: {{P: [0, 0, 0]}}
""")
    out.append("joints:\n")
    for i, (l, n, u, top) in enumerate(legs):
        k = i + 1
        out.append(f"""  - {{name: U{k}, type: universal, connects: [ground.B{k}, cylinder{k}.B], axes: [{v(u)}, [0, 0, 1]]}}
  - {{name: P{k}, type: prismatic, connects: [cylinder{k}.B, piston{k}.P], axis: [1, 0, 0]}}
  - {{name: S{k}, type: spherical, connects: [piston{k}.P, platform.P{k}]}}
""")
    out.append("""loads:
  - {name: payload, type: force, point: platform.C, force: [0, 0, -981], frame: world}
measures:
  - {name: platform_x, type: point, point: platform.C, component: x}
  - {name: platform_y, type: point, point: platform.C, component: y}
  - {name: platform_z, type: point, point: platform.C, component: z}
""")
    out.append("drivers:\n")
    for i, (l, n, u, top) in enumerate(legs):
        out.append(f"  - {{name: L{i + 1}, joint: P{i + 1}, profile: harmonic, initial: {num(l)}, "
                   f"amplitude: {num(amplitudes[i])}, frequency: 0.5}}\n")
    write("stewart-platform.yaml", "".join(out))


if __name__ == "__main__":
    bennett()
    bricard()
    hooke()
    slider_crank()
    heavy_top()
    rolling_disc()
    crank_rocker_3d()
    double_wishbone()
    stewart()
