// `orthomech render FILE --out X.svg|.png|.pdf`: the mechanism drawn at its design position (as
// `assemble` projects it), at a design position of the file (--position) or with the driver at a
// value (--input), through Cairo (io/render.hpp); a spatial one in an orthographic view (--view).
// docs/cli.md, "render".
#include "orthomech/io/render.hpp"

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <stdexcept>

#include "commands.hpp"
#include "common.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/io/file_writer.hpp"
#include "orthomech/io/units.hpp"

namespace orthomech::cli {

namespace {

struct RenderCliOptions {
  std::string file;
  std::vector<std::string> sets;  // --set PATH=VALUE
  std::string out;
  std::string position;
  std::string input;
  std::string view;  // --view: "" is iso for spatial files
  std::vector<std::string> traces;
  std::string from, to;  // --from, --to: the input range of --trace and --animate
  bool labels = false;
  bool animate = false;
  double duration = 4.0;
  int width = 800;
  int height = 600;
};

[[noreturn]] void bad(const std::string& what) {
  throw InputError({"command line", 0, 0}, "option", what);
}

// The sweep's input range of --trace and --animate from --from and --to (bare numbers in the
// file's declared units, as `cycle`); empty: the driver's full turn, or a prismatic driver's
// limits.
SweepRange sweep_range(const Model& model, int driver, const RenderCliOptions& opt) {
  SweepRange range;
  if (opt.from.empty() && opt.to.empty()) return range;
  if (driver < 0) bad("--from and --to need a driver and the file has none");
  const bool angular =
      joint_coordinate_kind(model.joints[static_cast<size_t>(driver)]) == CoordinateKind::angle;
  const UnitSystem file_units = unit_system(model.units);
  const double bare = angular ? file_units.angle_si : file_units.length_si;
  try {
    if (!opt.from.empty()) range.start = parse_position(opt.from, angular, bare);
    if (!opt.to.empty()) range.end = parse_position(opt.to, angular, bare);
  } catch (const std::invalid_argument& e) {
    bad(std::string(opt.from.empty() ? "--to" : "--from/--to") + ": " + e.what());
  }
  if (range.start && !range.end && !angular)
    bad("--to: a prismatic driver needs the end of the range (--to)");
  return range;
}

int run_render(const RenderCliOptions& opt) {
  const auto format = image_format_of(opt.out);
  if (!format) bad("--out: unknown image type '" + opt.out + "' (use .svg, .png or .pdf)");
  const Model model = load(opt.file, opt.sets);
  const ViewChoice view = choose_view(model, opt.view);
  if (!view.projection) bad(view.message);
  const PoseResult pose = assemble_pose(model, RenderPose{opt.position, opt.input});
  if (pose.status == PoseStatus::bad_request) bad(pose.message);
  if (pose.status == PoseStatus::cannot_assemble) {
    spdlog::error("{}: {}", model.file, pose.message);
    return kNumerical;
  }
  RenderOptions options;
  options.width = opt.width;
  options.height = opt.height;
  options.labels = opt.labels;
  options.driver = pose.driver;
  options.projection = *view.projection;
  int code = kOk;
  if ((!opt.from.empty() || !opt.to.empty()) && opt.traces.empty() && !opt.animate)
    bad("--from and --to give the range of --trace and --animate: give one of them");
  const SweepRange range = sweep_range(model, pose.driver, opt);
  if (!opt.traces.empty()) {
    TraceResult traced = trace_points(model, opt.traces, pose.driver, range);
    if (traced.status == TraceStatus::bad_request) bad(traced.message);
    if (traced.status == TraceStatus::failed) {
      spdlog::error("{}: {}", model.file, traced.message);
      return kNumerical;
    }
    if (traced.status == TraceStatus::partial) {
      // Drawn, but only up to where the sweep stopped: exit 1, as `cycle`.
      spdlog::warn("{}: the traces stop where the sweep stopped: {}", model.file, traced.message);
      code = kCheckFailed;
    }
    options.traces = std::move(traced.traces);
  }
  if (opt.animate) {
    if (*format != ImageFormat::svg) bad("--animate writes an SVG: give --out NAME.svg");
    const CyclePositions sweep = sweep_positions(model, pose.driver, range);
    if (sweep.status == TraceStatus::bad_request) bad(sweep.message);
    if (sweep.status == TraceStatus::failed) {
      spdlog::error("{}: {}", model.file, sweep.message);
      return kNumerical;
    }
    if (sweep.status == TraceStatus::partial) {
      spdlog::warn("{}: the animation stops where the sweep stopped: {}", model.file,
                   sweep.message);
      code = kCheckFailed;
    }
    try {
      write_file(opt.out, animated_svg(model, sweep.q, options, opt.duration));
    } catch (const std::runtime_error& e) {
      release_render_caches();
      spdlog::error("{}", e.what());
      return kBadInput;
    }
    release_render_caches();
    spdlog::info("wrote {} ({} frames)", opt.out, sweep.q.size());
    return code;
  }
  const Scene scene = build_scene(model, pose.q, options);
  try {
    write_image(scene, *format, opt.out);
  } catch (const std::runtime_error& e) {  // e.g. no such directory, no permission
    release_render_caches();
    spdlog::error("{}", e.what());
    return kBadInput;
  }
  release_render_caches();  // nothing left for a leak checker at exit
  spdlog::info("wrote {}", opt.out);
  return code;
}

}  // namespace

void register_render(CLI::App& app, const GlobalOptions& globals, int& exit_code) {
  auto opt = std::make_shared<RenderCliOptions>();
  CLI::App* cmd = app.add_subcommand(
      "render",
      "draw the mechanism (SVG, PNG or PDF by the extension of --out) at its design position, "
      "a design position of the file or a driver input");
  cmd->add_option("file", opt->file, "mechanism file (YAML)")->required();
  add_set_option(cmd, opt->sets);
  cmd->add_option("--out,-o", opt->out, "image file: .svg, .png or .pdf")->required();
  auto* position =
      cmd->add_option("--position", opt->position, "draw at this design position of the file");
  cmd->add_option("--input", opt->input,
                  "draw with the driver's joint at this value (30deg, 0.5rad, 12mm; a bare number "
                  "is in the file's units)")
      ->excludes(position);
  cmd->add_option("--trace", opt->traces,
                  "BODY.POINT: draw the path of this point over the driver's cycle (as `cycle` "
                  "sweeps it); repeatable");
  cmd->add_option("--from", opt->from,
                  "start input of --trace and --animate, e.g. 30deg, 20mm (a bare number is in "
                  "the file's units); default: the design position");
  cmd->add_option("--to", opt->to,
                  "end input of --trace and --animate: the range instead of a full turn; a "
                  "prismatic driver's default is its joint's limits");
  cmd->add_flag("--animate", opt->animate,
                "an SVG that plays the driver's cycle by itself, one frame per position");
  cmd->add_option("--duration", opt->duration, "seconds of one loop of --animate (default 4)")
      ->check(finite_range(0.0, 3600.0, true));
  cmd->add_option("--view", opt->view,
                  "spatial mechanisms: iso (default), front, top, side, or AZIMUTH,ELEVATION in "
                  "degrees (orthographic; a planar mechanism is drawn in its plane)");
  cmd->add_flag("--labels", opt->labels, "names of bodies, joints and points");
  cmd->add_option("--width", opt->width, "image width (px; pt in a PDF)")
      ->check(CLI::Range(200, 10000));
  cmd->add_option("--height", opt->height, "image height (px; pt in a PDF)")
      ->check(CLI::Range(200, 10000));
  cmd->callback([opt, &globals, &exit_code] {
    setup_logging(globals);
    exit_code = run_render(*opt);
  });
}

}  // namespace orthomech::cli
