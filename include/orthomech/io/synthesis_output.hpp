#pragma once
// The documents of a synthesis result (synthesis/synthesize.hpp; docs/cli.md, "synthesize"):
// the terminal table, candidates.csv, the JSON document and the report page. The library renders
// them; `orthomech synthesize` (cli/synthesize.cpp) only prints or writes what these return.
// Lengths in the task's length unit, angles in its angle unit, the drive torque in N·(length
// unit), forces in N.
#include <string>

#include "orthomech/synthesis/synthesize.hpp"
#include "orthomech/synthesis/task.hpp"

namespace orthomech {

// The table: the task, the generator's outcome, the tolerance, one row per candidate (accepted
// in rank order, then rejected with every reason). `files_dir` non-empty: a line naming the files
// written there.
[[nodiscard]] std::string synthesis_text(const synthesis::SynthesisTask& task,
                                         const synthesis::SynthesisResult& result,
                                         const std::string& files_dir = "");
// candidates.csv: one row per candidate, accepted first (ranked), then rejected with reasons.
[[nodiscard]] std::string synthesis_csv(const synthesis::SynthesisTask& task,
                                        const synthesis::SynthesisResult& result);
// The JSON document (schema: docs/cli.md, "JSON schema of synthesize"), indented by 2.
[[nodiscard]] std::string synthesis_json(const synthesis::SynthesisTask& task,
                                         const synthesis::SynthesisResult& result);

// The report page (`synthesize --report FILE.html`): one self-contained HTML page that works
// offline: the table, then one drawing (inline SVG) per candidate, accepted and rejected, with
// the targets — points as circles, poses as circles with an arrow along the pose's x axis,
// function targets as the follower's pin at the output angle — under the linkage at the first
// target and the coupler point's curve over the candidate's motion (its cycle's range; the
// targets' crank angles are vertices of the curve). The page's contract (the tests read it):
// each drawing is `svg.candidate` with `data-name`, and `data-view` = "s x0 y0": a model point
// (x, y) in the task's length unit is at pixel (x0 + s·x, y0 − s·y); each target is a
// `circle.target`, the curve a `polyline.curve`, the links `line.link`.
[[nodiscard]] std::string synthesis_report_html(const synthesis::SynthesisTask& task,
                                                const synthesis::SynthesisResult& result);

}  // namespace orthomech
