#pragma once
// Files written by `orthomech cycle --out DIR`: the per-position CSV and a gnuplot script that
// plots the drive and the reaction magnitudes versus the input (SVG and PNG).
#include <filesystem>
#include <string>
#include <vector>

#include "orthomech/analysis/cycle.hpp"
#include "orthomech/model/model.hpp"

namespace orthomech {

struct CycleColumns {
  int input_display = 2;        // 1-based CSV column of the input in display units (deg or mm)
  int drive = 0;                // 1-based CSV column of the drive
  std::vector<int> magnitudes;  // 1-based CSV columns of the reaction magnitudes
};

// One row per position: input (SI and display unit), time, every measure, the drive, every
// reaction component, every reaction magnitude; units in the header ("drive [N*m]"). Cells that
// are not reported are empty (drive_reported, component_reported: an unbridged singular position,
// a component diverging next to a bridged change point). Written
// atomically (temporary file, then rename). Throws std::runtime_error naming the file on failure.
CycleColumns write_cycle_csv(const std::filesystem::path& file, const Model& model,
                             const CycleResult& result,
                             const std::vector<ReactionMagnitude>& magnitudes, bool angular,
                             const std::string& drive_unit);

// A gnuplot script, next to the CSV, that writes drive.svg, drive.png, reactions.svg and
// reactions.png in its own directory. Throws std::runtime_error naming the file on failure.
void write_cycle_gnuplot(const std::filesystem::path& script, const std::string& csv_name,
                         const Model& model, const std::vector<ReactionMagnitude>& magnitudes,
                         const CycleColumns& columns, bool angular, const std::string& drive_unit);

// Writes `text` to `file` atomically. Throws std::runtime_error naming the file on failure.
void write_file_atomically(const std::filesystem::path& file, const std::string& text);

}  // namespace orthomech
