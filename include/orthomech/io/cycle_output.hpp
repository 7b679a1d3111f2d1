#pragma once
// Files written by `orthomech cycle --out DIR`: the per-position CSV and a gnuplot script that
// plots the drive and the reaction magnitudes versus the input (SVG and PNG).
#include <filesystem>
#include <string>
#include <vector>

#include "orthomech/analysis/cycle.hpp"
#include "orthomech/analysis/cycle_friction.hpp"
#include "orthomech/analysis/shaking.hpp"
#include "orthomech/io/noise.hpp"
#include "orthomech/io/units.hpp"
#include "orthomech/model/model.hpp"

namespace orthomech {

// ---- Positions for outputs -------------------------------------------------------------------
// The pose of every moving body (its frame's origin x, y and angle, as `pose:` in the file; a
// particle: x, y) and the world position of every named point of a moving body ("coupler.P.x",
// "coupler.P.y"), in this order.
struct PositionColumn {
  std::string name;  // "crank.x", "crank.angle", "coupler.P.y"
  Dimension dimension = Dimension::length;
};
[[nodiscard]] std::vector<PositionColumn> position_columns(const Model& model);
// Their values at q (SI), in position_columns order; out is resized.
void compute_output_positions(const Model& model, const VecX& q, std::vector<double>& out);

// Component i of a body's velocity parameters u and of u̇: names and dimensions. Planar rigid
// body: vx, vy, omega (ax, ay, alpha); particle: vx, vy; spatial body: vx, vy, vz of its centre
// of mass (world) and wx, wy, wz of its angular velocity in its body frame (ax … az, alpha_x …
// alpha_z).
struct VelocityComponent {
  const char* velocity;
  const char* acceleration;
  Dimension velocity_dimension, acceleration_dimension;
};
[[nodiscard]] const VelocityComponent& velocity_component(const Body& body, int i);

// The scale of every dimension over the rows of the cycle's CSV (inputs, times, measures,
// positions, velocities, accelerations, drive, reaction components and magnitudes, SI): the CSV
// and the JSON write a value at rounding noise for its dimension as 0 (io/noise.hpp).
[[nodiscard]] NoiseFloor cycle_noise_floor(const Model& model, const CycleResult& result,
                                           const std::vector<ReactionMagnitude>& magnitudes,
                                           bool angular);

struct CycleColumns {
  int input_display = 1;             // 1-based CSV column of the input
  int drive = 0;                     // 1-based CSV column of the drive
  std::vector<int> magnitudes;       // 1-based CSV columns of the reaction magnitudes
  std::vector<int> forces, moments;  // the magnitudes' columns that are forces, moments
};

// Columns added to cycle.csv (`cycle --trace`: "trace coupler.P.x", at the end; the shaking
// force: before `limits`): a name, its dimension, one SI value per position of the sweep and,
// when not empty, whether each is reported (an empty cell where not).
struct ExtraColumn {
  std::string name;
  Dimension dimension = Dimension::length;
  std::vector<double> values;
  std::vector<bool> reported;  // empty: every value
  bool before_limits = false;  // after the magnitudes, before `limits` (else at the end)
};

// The shaking force's and moment's columns (analysis/shaking.hpp), before `limits`: "shaking
// force x", "shaking force y" and "shaking moment z" (spatial: x, y, z of both), in the world
// frame; empty where the position's rates are not reported.
[[nodiscard]] std::vector<ExtraColumn> shaking_columns(const Model& model,
                                                       const ShakingSeries& series);

// The friction's columns (analysis/friction.hpp), before `limits`: "drive without friction"
// (N*m when `angular`, else N), each pin's "<joint> friction moment" and "friction power";
// none without friction.
[[nodiscard]] std::vector<ExtraColumn> friction_columns(const Model& model,
                                                        const CycleResult& result,
                                                        const FrictionSeries& series, bool angular);

// One row per position, every quantity in `units` (units in the header: "drive [N*mm]"):
// input, time, every measure, every body's pose and named point, every body's velocity and
// acceleration, the drive, every reaction component, every reaction magnitude, the `extra`
// columns marked before_limits, `limits` (the joints outside their limits there,
// space-separated; empty inside) and the other `extra` columns. Cells that are not
// reported are empty (drive_reported, component_reported: an unbridged singular position, a
// component diverging next to a bridged change point). Written through FileWriter
// (io/file_writer.hpp): rows streamed to a temporary file, put in place when complete. Throws
// std::runtime_error naming the file on failure.
CycleColumns write_cycle_csv(const std::filesystem::path& file, const Model& model,
                             const CycleResult& result,
                             const std::vector<ReactionMagnitude>& magnitudes, bool angular,
                             const UnitSystem& units, const std::vector<ExtraColumn>& extra = {});

// A gnuplot script, next to the CSV, that writes drive.svg, drive.png, reactions.svg and
// reactions.png in its own directory (forces and moments on separate axes; dead and singular
// positions marked; the speed in the title). Throws std::runtime_error naming the file on failure.
void write_cycle_gnuplot(const std::filesystem::path& script, const std::string& csv_name,
                         const Model& model, const CycleResult& result,
                         const std::vector<ReactionMagnitude>& magnitudes,
                         const CycleColumns& columns, bool angular, const UnitSystem& units,
                         const std::string& speed_text);

}  // namespace orthomech
