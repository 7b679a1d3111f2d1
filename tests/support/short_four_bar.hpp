#pragma once
// A four-bar whose links are too short to close: 1 + 2 + 3 < 10 (gap 4 m = 4000 mm). Used by the
// position solver's and the assemble command's tests of a loop that cannot close.

namespace orthomech::test {

inline const char* const kShortFourBar = R"(orthomech: 1
name: short
ground:
  points: {A0: [0, 0], B0: [10, 0]}
bodies:
  - {name: crank, mass: 1, inertia: 0.1, pose: [0, 0, 0.5], points: {A0: [0, 0], A: [1, 0]}}
  - {name: coupler, mass: 1, inertia: 0.1, pose: [1, 0, 0.2], points: {A: [0, 0], B: [2, 0]}}
  - {name: rocker, mass: 1, inertia: 0.1, pose: [10, 0, 2.5], points: {B0: [0, 0], B: [3, 0]}}
joints:
  - {name: A0, type: revolute, connects: [ground.A0, crank.A0]}
  - {name: A, type: revolute, connects: [crank.A, coupler.A]}
  - {name: B, type: revolute, connects: [coupler.B, rocker.B]}
  - {name: B0, type: revolute, connects: [rocker.B0, ground.B0]}
)";

}  // namespace orthomech::test
