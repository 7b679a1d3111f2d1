#pragma once
// A "zoo" mechanism holding every joint, load and measure type, at a pose that is NOT assembled
// (f, Eᵀ, Dᵀ, loads and measures are defined everywhere, so finite-difference checks need no
// assembly). Used by the central-difference tests.
#include <string>

namespace orthomech::test {

inline const std::string kZooYaml = R"(
orthomech: 1
name: zoo
ground:
  points: {O: [0, 0], S: [0.3, -0.2], C: [0.5, 0.4]}
bodies:
  - {name: a, mass: 1.3, inertia: 0.02, com: [0.2, 0.05], pose: [0.01, -0.02, 0.4],
     points: {O: [0, 0], P: [0.4, 0.1], Q: [0.3, -0.2]}}
  - {name: b, mass: 0.7, inertia: 0.011, com: [0.1, 0], pose: [0.35, 0.2, -0.7],
     points: {P: [0, 0], R: [0.25, 0.05]}}
  - {name: c, mass: 2.1, inertia: 0.05, com: [0.0, 0.1], pose: [0.6, -0.1, 1.9],
     points: {Q: [0.05, 0.02], T: [0.2, 0.3]}}
  - {name: p, type: particle, mass: 0.4, pose: [0.9, 0.3]}
joints:
  - {name: J1, type: revolute, connects: [ground.O, a.O]}
  - {name: J2, type: prismatic, connects: [a.P, b.P], axis: [0.6, 0.8], angle: 0.3}
  - {name: J3, type: fixed, connects: [b.R, c.Q], angle: -0.4}
  - {name: J4, type: pin-in-slot, connects: [c.T, a.Q], axis: [1, 0.5]}
  - {name: J5, type: gear, bodies: [a, b], ratio: -1.7, carrier: c}
  - {name: J6, type: distance, connects: [b.R, p.origin], length: 0.5}
  - {name: J7, type: revolute, connects: [c.T, p.origin]}
  - {name: J8, type: prismatic, connects: [ground.S, c.Q], axis: [0, 1]}
  - {name: J9, type: pin-in-slot, connects: [ground.C, b.R], axis: [1, -1]}
measures:
  - {name: m_rev, type: joint, joint: J1}
  - {name: m_pri, type: joint, joint: J2}
  - {name: m_pri_ground, type: joint, joint: J8}
  - {name: m_px, type: point, point: c.T, component: x}
  - {name: m_py, type: point, point: b.R, component: y}
  - {name: m_pp, type: point, point: p.origin, component: y}
  - {name: m_dist, type: distance, points: [a.P, c.T]}
  - {name: m_ang, type: angle, body: b}
  - {name: m_rel, type: angle, bodies: [a, c]}
loads:
  - {name: weight, type: gravity, g: [0.3, -9.81]}
  - {name: push, type: force, point: b.R, force: [3, -2], frame: body,
     table: {measure: m_rev, points: [[-1, 0.5], [2, 1.5]]}}
  - {name: pull, type: force, point: p.origin, force: [-1, 4]}
  - {name: twist, type: torque, body: c, torque: 0.7}
  - {name: spring, type: spring-damper, connects: [a.Q, ground.C], stiffness: 120, free_length: 0.2, damping: 3}
  - {name: spring2, type: spring-damper, connects: [p.origin, c.T], stiffness: 50, free_length: 0.1, damping: 0}
  - {name: coil, type: rotary-spring-damper, bodies: [a, c], stiffness: 4, free_angle: 0.2, damping: 0.5}
)";

}  // namespace orthomech::test
