#include "orthomech/io/synthesis_output.hpp"

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "orthomech/synthesis/rssr.hpp"
#include "orthomech/synthesis/slider_crank.hpp"

namespace orthomech {

namespace {

using synthesis::SynthesisCandidate;
using synthesis::SynthesisResult;
using synthesis::SynthesisTask;

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

nlohmann::json xyz(const synthesis::Vec3& v, double unit) {
  return {v.x() / unit, v.y() / unit, v.z() / unit};
}

// An RSSR's axes (points in length units, unit directions and references), spherical centres in
// the cranks' frames (L50), coupler length and branch.
void rssr_json(nlohmann::json& j, const synthesis::Rssr& r, const SynthesisCandidate& c,
               const SynthesisTask& t) {
  const double L = t.length_si;
  for (const auto* ax : {&r.input, &r.output}) {
    const synthesis::Mat3 E = synthesis::axis_frame(*ax);
    j[ax == &r.input ? "input_axis" : "output_axis"] = {{"point", xyz(ax->point, L)},
                                                        {"direction", xyz(E.col(2), 1.0)},
                                                        {"ref", xyz(E.col(0), 1.0)}};
  }
  j["a"] = xyz(r.a, L);
  j["b"] = xyz(r.b, L);
  j["coupler"] = r.coupler / L;
  j["branch"] = r.branch;
  j["full_turn"] = synthesis::input_turns_fully(r);
  j["max_angle_error"] = c.max_angle_error / t.angle_si;
}

void four_bar_json(nlohmann::json& j, const synthesis::FourBar& fb, const SynthesisCandidate& c,
                   const SynthesisTask& t) {
  const double L = t.length_si;
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
  if (const auto* sc = std::get_if<synthesis::SliderCrank>(&c.linkage))
    slider_json(j, *sc, t);
  else if (const auto* r = std::get_if<synthesis::Rssr>(&c.linkage))
    rssr_json(j, *r, c, t);
  else
    four_bar_json(j, std::get<synthesis::FourBar>(c.linkage), c, t);
  if (c.cycle) {  // what `cycle` computes on the file, in its units (N*mm in an mm file, N)
    j["cycle"] = {{"from", c.cycle->from / t.angle_si}, {"to", c.cycle->to / t.angle_si},
                  {"positions", c.cycle->positions},    {"peak_drive", c.cycle->peak_drive / L},
                  {"drive_unit", "N*" + t.length_unit}, {"peak_pin_force", c.cycle->peak_pin_force},
                  {"peak_pin", c.cycle->peak_pin},      {"force_unit", "N"}};
  } else {
    j["cycle"] = nullptr;
  }
  return j;
}

std::string text_row(const SynthesisCandidate& c, const SynthesisTask& t) {
  const double L = t.length_si;
  char row[256], peaks[64] = "        -         -";
  if (c.cycle)
    std::snprintf(peaks, sizeof peaks, "%9.4g %9.4g", c.cycle->peak_drive / L,
                  c.cycle->peak_pin_force);
  if (const auto* sc = std::get_if<synthesis::SliderCrank>(&c.linkage)) {
    std::snprintf(row, sizeof row, "%-13s %9.4g %9.4g %9.4g %9s  %-22s %7.2f  %9.3g %s",
                  c.name.c_str(), sc->offset / L, sc->r / L, sc->l / L, "-",
                  synthesis::crank_turns_fully(*sc) ? "crank turns fully" : "crank rocks",
                  c.worst_transmission / kDeg, c.max_distance / L, peaks);
    return row;
  }
  if (const auto* r = std::get_if<synthesis::Rssr>(&c.linkage)) {
    const double ra = std::hypot(r->a.x(), r->a.y()), rb = std::hypot(r->b.x(), r->b.y());
    std::snprintf(row, sizeof row, "%-13s %9.4g %9.4g %9.4g %9.3g  %-22s %7.2f  %9.3g %s",
                  c.name.c_str(), r->coupler / L, ra / L, rb / L, c.max_angle_error / kDeg,
                  synthesis::input_turns_fully(*r) ? "input turns fully" : "input rocks",
                  c.worst_transmission / kDeg, c.max_distance / L, peaks);
    return row;
  }
  const auto& fb = std::get<synthesis::FourBar>(c.linkage);
  std::snprintf(row, sizeof row, "%-13s %9.4g %9.4g %9.4g %9.4g  %-22s %7.2f  %9.3g %s",
                c.name.c_str(), (fb.B0 - fb.A0).norm() / L, fb.a / L, fb.b / L, fb.c / L,
                synthesis::to_string(c.grashof), c.worst_transmission / kDeg, c.max_distance / L,
                peaks);
  return row;
}

// A candidate's CSV columns after name and accepted, up to max_distance.
void csv_linkage(std::ostringstream& out, const SynthesisCandidate& c, const SynthesisTask& t) {
  const double L = t.length_si;
  if (const auto* sc = std::get_if<synthesis::SliderCrank>(&c.linkage)) {
    out << sc->r / L << ',' << sc->l / L << ',' << sc->offset / L << ',' << sc->O.x() / L << ','
        << sc->O.y() / L << ',' << sc->line_angle / t.angle_si << ',' << sc->coupler_point.x() / L
        << ',' << sc->coupler_point.y() / L << ',' << sc->branch << ','
        << (synthesis::crank_turns_fully(*sc) ? 1 : 0) << ',';
  } else if (const auto* r = std::get_if<synthesis::Rssr>(&c.linkage)) {
    out << r->coupler / L << ',' << r->a.x() / L << ',' << r->a.y() / L << ',' << r->a.z() / L
        << ',' << r->b.x() / L << ',' << r->b.y() / L << ',' << r->b.z() / L << ',' << r->branch
        << ',' << (synthesis::input_turns_fully(*r) ? 1 : 0) << ','
        << c.max_angle_error / t.angle_si << ',';
  } else {
    const auto& fb = std::get<synthesis::FourBar>(c.linkage);
    out << (fb.B0 - fb.A0).norm() / L << ',' << fb.a / L << ',' << fb.b / L << ',' << fb.c / L
        << ',' << fb.A0.x() / L << ',' << fb.A0.y() / L << ',' << fb.B0.x() / L << ','
        << fb.B0.y() / L << ',' << fb.coupler_point.x() / L << ',' << fb.coupler_point.y() / L
        << ',' << fb.branch << ',' << synthesis::to_string(c.grashof) << ',';
  }
  out << c.worst_transmission / t.angle_si << ',' << c.max_distance / L << ',';
}

}  // namespace

std::string synthesis_text(const SynthesisTask& t, const SynthesisResult& r,
                           const std::string& files_dir) {
  std::ostringstream out;
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
  if (!files_dir.empty())
    out << "files           " << files_dir << "/candidate-K.yaml, candidates.csv\n";
  if (t.linkage == synthesis::TaskLinkage::slider_crank)
    out << "\nname               offset     crank       rod            type                   "
           "mu_min  max_dist     drive  pin_force\n";
  else if (t.linkage == synthesis::TaskLinkage::rssr)
    out << "\nname              coupler   r_input  r_output  psi_err  type                   "
           "mu_min  max_dist     drive  pin_force\n";
  else
    out << "\nname               ground     crank   coupler  follower  grashof                "
           "mu_min  max_dist     drive  pin_force\n";
  out << "                   [" << t.length_unit << "]                                  "
      << "                    [deg]  [" << t.length_unit << "]   [N*" << t.length_unit
      << "]       [N]\n";
  for (const auto& c : r.accepted) out << text_row(c, t) << "\n";
  for (const auto& c : r.rejected) {
    out << text_row(c, t) << "\n";
    for (const auto& why : c.rejections) out << "    rejected: " << why << "\n";
  }
  return out.str();
}

std::string synthesis_csv(const SynthesisTask& t, const SynthesisResult& r) {
  std::ostringstream out;
  out.precision(17);
  if (t.linkage == synthesis::TaskLinkage::slider_crank)
    out << "name,accepted,crank,rod,offset,O_x,O_y,line_angle,P_p,P_q,branch,full_turn,";
  else if (t.linkage == synthesis::TaskLinkage::rssr)
    out << "name,accepted,coupler,a_x,a_y,a_z,b_x,b_y,b_z,branch,full_turn,max_angle_error,";
  else
    out << "name,accepted,ground,crank,coupler,follower,A0_x,A0_y,B0_x,B0_y,P_p,P_q,branch,"
           "grashof,";
  out << "worst_transmission,max_distance,peak_drive,peak_pin_force,reasons\n";
  const double L = t.length_si;
  for (const auto* list : {&r.accepted, &r.rejected})
    for (const auto& c : *list) {
      std::string reasons;
      for (const auto& why : c.rejections) reasons += (reasons.empty() ? "" : "; ") + why;
      for (char& ch : reasons)
        if (ch == '"') ch = '\'';
      out << c.name << ',' << (c.accepted() ? 1 : 0) << ',';
      csv_linkage(out, c, t);
      if (c.cycle)
        out << c.cycle->peak_drive / L << ',' << c.cycle->peak_pin_force;
      else
        out << ',';
      out << ",\"" << reasons << "\"\n";
    }
  return out.str();
}

std::string synthesis_json(const SynthesisTask& task, const SynthesisResult& r) {
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
  return j.dump(2);
}

}  // namespace orthomech
