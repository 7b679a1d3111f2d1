// `orthomech synthesize TASK [--out DIR] [--json]`: planar four-bars (or slider-cranks, task key
// `linkage`) from the motion, path or input–output law a designer wants (issue 50; docs/cli.md
// "synthesize"). The library runs the task and validates every candidate
// (synthesis/synthesize.hpp); this file only renders the result and writes the accepted
// candidates' mechanism files. Exit 0 when a candidate is accepted, 1 when every one is
// rejected, 3 when the generator finds no linkage.
#include "orthomech/synthesis/synthesize.hpp"

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "commands.hpp"
#include "common.hpp"
#include "orthomech/io/file_writer.hpp"
#include "orthomech/synthesis/slider_crank.hpp"

namespace orthomech::cli {

namespace {

using synthesis::SynthesisCandidate;
using synthesis::SynthesisResult;
using synthesis::SynthesisTask;

struct SynthesizeCliOptions {
  std::string file;
  std::string out;
  bool json = false;
};

constexpr double kDeg = std::numbers::pi / 180.0;

// A slider-crank's lengths and placement (task key `linkage: slider-crank`).
void slider_json(nlohmann::json& j, const synthesis::SliderCrank& sc, const SynthesisTask& t) {
  const double L = t.length_si;
  j["O"] = {sc.O.x() / L, sc.O.y() / L};
  j["line_angle"] = sc.line_angle / t.angle_si;
  j["crank"] = sc.r / L;
  j["rod"] = sc.l / L;
  j["offset"] = sc.offset / L;
  j["coupler_point"] = {sc.coupler_point.x() / L, sc.coupler_point.y() / L};
  j["branch"] = sc.branch;
  j["full_turn"] = synthesis::crank_turns_fully(sc);
}

nlohmann::json candidate_json(const SynthesisCandidate& c, const SynthesisTask& t) {
  const double L = t.length_si;
  nlohmann::json j;
  j["name"] = c.name;
  j["method"] = c.method;
  j["accepted"] = c.accepted();
  j["rejections"] = c.rejections;
  j["worst_transmission"] = c.worst_transmission / t.angle_si;
  j["max_distance"] = c.max_distance / L;
  nlohmann::json angles = nlohmann::json::array();
  for (const double a : c.crank_angles) angles.push_back(a / t.angle_si);
  j["crank_angles"] = angles;
  if (const auto* sc = std::get_if<synthesis::SliderCrank>(&c.linkage)) {
    slider_json(j, *sc, t);
    return j;
  }
  const auto& fb = std::get<synthesis::FourBar>(c.linkage);
  j["A0"] = {fb.A0.x() / L, fb.A0.y() / L};
  j["B0"] = {fb.B0.x() / L, fb.B0.y() / L};
  j["crank"] = fb.a / L;
  j["coupler"] = fb.b / L;
  j["follower"] = fb.c / L;
  j["ground"] = (fb.B0 - fb.A0).norm() / L;
  j["coupler_point"] = {fb.coupler_point.x() / L, fb.coupler_point.y() / L};
  j["branch"] = fb.branch;
  j["grashof"] = synthesis::to_string(c.grashof);
  j["max_angle_error"] = c.max_angle_error / t.angle_si;
  return j;
}

std::string text_row(const SynthesisCandidate& c, const SynthesisTask& t) {
  const double L = t.length_si;
  char row[256];
  if (const auto* sc = std::get_if<synthesis::SliderCrank>(&c.linkage)) {
    std::snprintf(row, sizeof row, "%-13s %9.4g %9.4g %9.4g %9s  %-22s %7.2f  %9.3g",
                  c.name.c_str(), sc->offset / L, sc->r / L, sc->l / L, "-",
                  synthesis::crank_turns_fully(*sc) ? "crank turns fully" : "crank rocks",
                  c.worst_transmission / kDeg, c.max_distance / L);
    return row;
  }
  const auto& fb = std::get<synthesis::FourBar>(c.linkage);
  std::snprintf(row, sizeof row, "%-13s %9.4g %9.4g %9.4g %9.4g  %-22s %7.2f  %9.3g",
                c.name.c_str(), (fb.B0 - fb.A0).norm() / L, fb.a / L, fb.b / L, fb.c / L,
                synthesis::to_string(c.grashof), c.worst_transmission / kDeg, c.max_distance / L);
  return row;
}

void write_text(std::ostream& out, const SynthesisTask& t, const SynthesisResult& r,
                const std::string& dir) {
  out << "task            " << t.name << "  (" << t.file << "), " << to_string(t.kind)
      << " generation, "
      << (t.kind == synthesis::TaskKind::function ? t.inputs.size() : t.positions.size())
      << " targets\n";
  out << "generator       " << synthesis::to_string(r.status)
      << (r.message.empty() ? "" : ": " + r.message) << "\n";
  out << "tolerance       " << r.tolerance / t.length_si << " " << t.length_unit
      << " (distance of a candidate from a target)\n";
  out << "candidates      " << r.accepted.size() << " accepted, " << r.rejected.size()
      << " rejected (every one validated; ranked by " << t.rank_by << ")\n";
  if (!dir.empty()) out << "files           " << dir << "/candidate-K.yaml, candidates.csv\n";
  if (t.linkage == synthesis::TaskLinkage::slider_crank)
    out << "\nname               offset     crank       rod            type                   "
           "mu_min  max_dist\n";
  else
    out << "\nname               ground     crank   coupler  follower  grashof                "
           "mu_min  max_dist\n";
  out << "                   [" << t.length_unit << "]                                  "
      << "                    [deg]  [" << t.length_unit << "]\n";
  for (const auto& c : r.accepted) out << text_row(c, t) << "\n";
  for (const auto& c : r.rejected) {
    out << text_row(c, t) << "\n";
    for (const auto& why : c.rejections) out << "    rejected: " << why << "\n";
  }
}

// candidates.csv: one row per candidate, accepted first (ranked), then rejected with reasons.
std::string csv_text(const SynthesisResult& r, const SynthesisTask& t) {
  std::ostringstream out;
  out.precision(17);
  const bool slider = t.linkage == synthesis::TaskLinkage::slider_crank;
  if (slider)
    out << "name,accepted,crank,rod,offset,O_x,O_y,line_angle,P_p,P_q,branch,full_turn,"
           "worst_transmission,max_distance,reasons\n";
  else
    out << "name,accepted,ground,crank,coupler,follower,A0_x,A0_y,B0_x,B0_y,P_p,P_q,branch,"
           "grashof,worst_transmission,max_distance,reasons\n";
  const double L = t.length_si;
  for (const auto* list : {&r.accepted, &r.rejected})
    for (const auto& c : *list) {
      std::string reasons;
      for (const auto& why : c.rejections) reasons += (reasons.empty() ? "" : "; ") + why;
      for (char& ch : reasons)
        if (ch == '"') ch = '\'';
      if (const auto* sc = std::get_if<synthesis::SliderCrank>(&c.linkage)) {
        out << c.name << ',' << (c.accepted() ? 1 : 0) << ',' << sc->r / L << ',' << sc->l / L
            << ',' << sc->offset / L << ',' << sc->O.x() / L << ',' << sc->O.y() / L << ','
            << sc->line_angle / t.angle_si << ',' << sc->coupler_point.x() / L << ','
            << sc->coupler_point.y() / L << ',' << sc->branch << ','
            << (synthesis::crank_turns_fully(*sc) ? 1 : 0) << ','
            << c.worst_transmission / t.angle_si << ',' << c.max_distance / L << ",\"" << reasons
            << "\"\n";
        continue;
      }
      const auto& fb = std::get<synthesis::FourBar>(c.linkage);
      out << c.name << ',' << (c.accepted() ? 1 : 0) << ',' << (fb.B0 - fb.A0).norm() / L << ','
          << fb.a / L << ',' << fb.b / L << ',' << fb.c / L << ',' << fb.A0.x() / L << ','
          << fb.A0.y() / L << ',' << fb.B0.x() / L << ',' << fb.B0.y() / L << ','
          << fb.coupler_point.x() / L << ',' << fb.coupler_point.y() / L << ',' << fb.branch << ','
          << synthesis::to_string(c.grashof) << ',' << c.worst_transmission / t.angle_si << ','
          << c.max_distance / L << ",\"" << reasons << "\"\n";
    }
  return out.str();
}

int run_synthesize(const SynthesizeCliOptions& opt) {
  const SynthesisTask task = synthesis::load_synthesis_task(opt.file);
  const SynthesisResult r = synthesis::run_synthesis(task);
  if (!opt.out.empty()) {
    try {
      std::filesystem::create_directories(opt.out);
      for (const auto& c : r.accepted)
        write_file(std::filesystem::path(opt.out) / (c.name + ".yaml"), c.file_text);
      write_file(std::filesystem::path(opt.out) / "candidates.csv", csv_text(r, task));
    } catch (const std::exception& e) {  // no such directory, no permission, a full disk
      spdlog::error("synthesize: --out {}: {}", opt.out, e.what());
      return kBadInput;
    }
  }
  if (opt.json) {
    nlohmann::json j;
    j["task"] = task.name;
    j["kind"] = to_string(task.kind);
    j["units"] = {{"length", task.length_unit}, {"angle", task.angle_unit}};
    j["generator"] = {{"status", synthesis::to_string(r.status)}, {"message", r.message}};
    j["tolerance"] = r.tolerance / task.length_si;
    j["rank_by"] = task.rank_by;
    nlohmann::json acc = nlohmann::json::array(), rej = nlohmann::json::array();
    for (const auto& c : r.accepted) acc.push_back(candidate_json(c, task));
    for (const auto& c : r.rejected) rej.push_back(candidate_json(c, task));
    j["accepted"] = acc;
    j["rejected"] = rej;
    std::cout << j.dump(2) << '\n';
  } else {
    write_text(std::cout, task, r, opt.out);
  }
  std::cout.flush();
  if (r.accepted.empty() && r.rejected.empty()) {
    spdlog::error("synthesize: {}: no {}: {}", task.file, to_string(task.linkage), r.message);
    return kNumerical;
  }
  if (r.accepted.empty()) {
    spdlog::error("synthesize: {}: every candidate is rejected (the reasons are listed)",
                  task.file);
    return kCheckFailed;
  }
  return kOk;
}

}  // namespace

void register_synthesize(CLI::App& app, const GlobalOptions& globals, int& exit_code) {
  auto opt = std::make_shared<SynthesizeCliOptions>();
  CLI::App* cmd = app.add_subcommand(
      "synthesize",
      "planar four-bars from coupler poses, coupler points or an input-output law, each validated");
  cmd->add_option("task", opt->file, "synthesis task file (YAML, docs/file-format.md)")->required();
  cmd->add_option("--out", opt->out,
                  "directory for the accepted candidates' mechanism files and candidates.csv");
  cmd->add_flag("--json", opt->json, "one JSON document on stdout");
  auto log = std::make_shared<LogFlags>();
  add_log_flags(cmd, *log);
  cmd->callback([opt, log, &globals, &exit_code] {
    setup_logging(globals, *log);
    exit_code = run_synthesize(*opt);
  });
}

}  // namespace orthomech::cli
