#pragma once
// `orthomech cycle --report FILE.html` (issue 14): one self-contained HTML page that works
// offline — the cycle's terminal summary, the drive and reaction plots versus the input, and the
// animation of the cycle (io/render.hpp animated_svg), with a slider and a play button that move
// the mechanism and a cursor on every plot together; hovering a plot shows the values there.
//
// The plots are drawn by a small script of the page into inline SVG (no plotting library: a
// polyline per series, axes, a cursor and a tooltip are about 150 lines, with no licence to carry
// and nothing to fetch). The page's contract (docs/cli.md, "cycle --report"; the browser tests
// read it): the animation's frames are the groups `g[id^="frame-"]` of `#mechanism svg`, exactly
// one shown (display="inline") at a time, the others display="none"; the slider is
// `input#position` (0 … N − 1); the button `#play`; each plot `svg.plot` with a `line.cursor` at
// the shown position; the tooltip `#tooltip`; `body[data-ready="yes"]` once the script ran and
// `window.reportErrors` lists the script errors met.
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace orthomech {

struct ReportSeries {
  std::string name;                           // "drive", "A.|F|"
  std::vector<std::optional<double>> values;  // one per position (output units); none: not
                                              // reported there
};
struct ReportPlot {
  std::string id;     // the plot's element id is "plot-" + id
  std::string title;  // "drive torque"
  std::string unit;   // "N*mm"
  std::vector<ReportSeries> series;
};
struct CycleReport {
  std::string title;          // the mechanism's name
  std::string summary;        // the terminal summary of `cycle`, shown as is
  std::string input_label;    // "input [deg]"
  std::vector<double> input;  // the input at each position, output units
  std::vector<ReportPlot> plots;
  std::string animation;  // animated_svg of the same positions (one frame per position)
  double duration = 4.0;  // s per loop of the play button
};

// Pictures of many positions (animated_svg's frames, the report's plots and slider) show at most
// kMaxPictureFrames of them: the positions picture_positions(n) gives, evenly spaced over the n,
// the first and the last included (all n when n ≤ kMaxPictureFrames). The page of a 100000-step
// cycle stays a few MB instead of 1.3 GB; every position stays in the CSV and JSON outputs.
inline constexpr std::size_t kMaxPictureFrames = 1000;
[[nodiscard]] std::vector<std::size_t> picture_positions(std::size_t n);

// Text for HTML element content and attribute values: & < > " escaped.
[[nodiscard]] std::string escape_html(const std::string& s);

// The page. Throws std::invalid_argument when a series does not have one value per position or
// the animation not one frame per picture position (picture_positions of the positions).
[[nodiscard]] std::string cycle_report_html(const CycleReport& report);

}  // namespace orthomech
