#pragma once
// Published reference values of Andrews' squeezing mechanism (../shared/references.md §1: Test
// Set for IVP Solvers, problem `andrews`; Hairer & Wanner, Solving ODEs II, §VII.7), in the test
// set's coordinates (β, Θ, γ, Φ, δ, Ω, ε) and sign convention of λ (M q̈ − f + Gᵀλ = 0). One
// copy for the tests, the benchmarks and the peer programs (bench/peers, which do not link
// orthomech): constants only.
#include <array>

namespace orthomech::test::andrews {

// Consistent initial angles at t = 0 (exact to the digits printed).
inline constexpr std::array<double, 7> kAnglesT0 = {
    -0.0617138900142764496358948458001, 0.0,
    0.455279819163070380255912382449,   0.222668390165885884674473185609,
    0.487364979543842550225598953530,   -0.222668390165885884674473185609,
    1.23054744454982119249735015568};

// The state at t = 0.03 s (PSIDE, rtol = atol = 1e-14).
inline constexpr std::array<double, 7> kAnglesT003 = {
    15.81077119629904,  -15.75637105984298, 0.04082224013073101, -0.5347301163226948,
    0.5244099658805304, 0.5347301163226948, 1.048080741042263};
inline constexpr std::array<double, 7> kRatesT003 = {
    1139.920302151208,  -1424.379294994111, 11.03291221937134, 19.29337464421385,
    0.5735699284790808, -19.29337464421385, 0.3231791658026955};
inline constexpr std::array<double, 6> kLambdaT003 = {199.1753333731910, -29.75531228015052,
                                                      23.06654119098399, 31.45271365475927,
                                                      22.64249232082739, 11.61740700019673};

// Published tolerances: positions 1e-8, velocities 1e-5, multipliers 1e-4 (all relative).
inline constexpr double kAngleTol = 1e-8;
inline constexpr double kRateTol = 1e-5;
inline constexpr double kLambdaTol = 1e-4;

}  // namespace orthomech::test::andrews
