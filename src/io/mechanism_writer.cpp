#include "orthomech/io/mechanism_writer.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "orthomech/check.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/error.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/io/noise.hpp"
#include "orthomech/io/units.hpp"
#include "orthomech/model/spatial.hpp"

namespace orthomech {

namespace {

// Unit factors (SI per file unit), as in docs/file-format.md; only length and angle appear in
// a pose.
double unit_factor(const YAML::Node& units, const std::string& key, const std::string& origin) {
  if (!units || !units[key]) return 1.0;
  const std::string u = units[key].Scalar();
  static const std::vector<std::pair<std::string, double>> table = {
      {"m", 1.0},
      {"cm", 0.01},
      {"mm", 0.001},
      {"in", 0.0254},
      {"ft", 0.3048},
      {"rad", 1.0},
      {"deg", std::numbers::pi / 180.0}};
  for (const auto& [name, f] : table)
    if (name == u) return f;
  throw InputError({origin, 0, 0}, "units", "unknown " + key + " unit '" + u + "'");
}

// A pose number as written: rounded to 15 significant digits (the 16th and 17th of an assembled
// pose are rounding noise: 29.999999999999996 is written 30), in its shortest form.
std::string written_number(double v) {
  char rounded[32];
  std::snprintf(rounded, sizeof rounded, "%.15g", v);
  const double w = std::strtod(rounded, nullptr);
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, w == 0.0 ? 0.0 : w);  // never "-0"
  return std::string(buf, r.ptr);
}

struct Edit {
  size_t begin, end;
  std::string text;
};

// How many times each scalar of the document is reached from the root, by its offset in the
// text: more than once when it is (or lies inside) an anchored node reused through an alias.
void count_uses(const YAML::Node& node, std::map<int, int>& uses, int depth = 0) {
  if (depth > 200) return;  // the reader accepted the file; yaml-cpp itself limits nesting
  if (node.IsScalar()) {
    ++uses[node.Mark().pos];
  } else if (node.IsSequence()) {
    for (const auto& item : node) count_uses(item, uses, depth + 1);
  } else if (node.IsMap()) {
    for (const auto& kv : node) {
      count_uses(kv.first, uses, depth + 1);
      count_uses(kv.second, uses, depth + 1);
    }
  }
}

// The written text must re-read as the model with the new design poses: the same elements, the
// same masses, inertias, centres of mass and points (bit for bit: their text is unchanged), and
// every body frame within kRoundTrip of the one asked for. The written numbers are the value in
// file units rounded to 15 significant digits (5e-16 relative) and rounding noise as 0 (2.6e-13
// of the mechanism's size, 1.8e-13 rad); reading multiplies by the unit factor once: a few ulps.
// All of it far below 1e-12 (m or rad) for the limits of docs/file-format.md (|x| <= 1e6).
constexpr double kRoundTrip = 1e-12;

// A pose number written as an expression of the parameters (`a/2`, docs/file-format.md
// "Parameters") keeps its text when the assembly left it where it was: within a tenth of
// kRoundTrip (m or rad, against the same scale), so that the re-read file still passes
// verify_written; it is replaced by a number (and listed in PoseEdit::replaced_expressions) when
// the assembly moved it.
constexpr double kKeptExpression = kRoundTrip / 10;

bool is_plain_number(const std::string& s) {
  if (s.empty()) return false;
  char* end = nullptr;
  (void)std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size();
}

// The expression text of `v` is kept: v is an expression whose value `before` (SI) the assembly
// did not change (`after`).
bool keeps_expression(const YAML::Node& v, double before, double after, double scale) {
  return v.IsScalar() && !is_plain_number(v.Scalar()) &&
         std::abs(after - before) <= kKeptExpression * std::max(1.0, scale);
}

Model verify_written(const std::string& written, const std::string& origin, const Model& model,
                     const std::vector<Vec3>& frames) {
  Model back;
  try {
    back = parse_mechanism(written, origin);
  } catch (const InputError& e) {
    throw InputError(
        {origin, 1, 1}, "file",
        "the edited file would not read back (" + e.message() + "); nothing was written");
  }
  const auto differ = [&](const std::string& what) {
    throw InputError({origin, 1, 1}, "file",
                     "the edited file would not read back as the assembled mechanism (" + what +
                         " differs); nothing was written");
  };
  if (back.bodies.size() != model.bodies.size() || back.joints.size() != model.joints.size() ||
      back.loads.size() != model.loads.size() || back.measures.size() != model.measures.size() ||
      back.drivers.size() != model.drivers.size() ||
      back.design_positions.size() != model.design_positions.size() || back.nq != model.nq ||
      back.nc != model.nc)
    differ("the number of elements");
  for (size_t b = 0; b < model.bodies.size(); ++b) {
    const Body &x = model.bodies[b], &y = back.bodies[b];
    if (x.name != y.name || x.kind != y.kind || x.mass != y.mass || x.inertia != y.inertia ||
        x.com_local != y.com_local || x.points != y.points)
      differ("body '" + x.name + "'");
    if (x.kind == BodyKind::spatial) continue;  // verify_spatial
    const Vec3 d = y.design_pose - frames[b];
    const double scale = std::max(1.0, frames[b].head<2>().cwiseAbs().maxCoeff());
    if (!(std::abs(d.x()) <= kRoundTrip * scale && std::abs(d.y()) <= kRoundTrip * scale &&
          std::abs(d.z()) <= kRoundTrip * std::max(1.0, std::abs(frames[b].z()))))
      differ("the pose of body '" + x.name + "'");
  }
  for (size_t j = 0; j < model.joints.size(); ++j)
    if (model.joints[j].name != back.joints[j].name ||
        model.joints[j].type_name() != back.joints[j].type_name())
      differ("joint '" + model.joints[j].name + "'");
  return back;
}

// A spatial body's frame as written: its origin in world and its orientation (unit quaternion).
struct WrittenFrame {
  Vec3 origin;
  Quat orientation;
};

// The spatial part of verify_written: every body's inertia and points bit for bit, its frame
// within kRoundTrip (origin against the mechanism's size, orientation as the largest change of an
// entry of R), and the joints closed at the written design pose as well as at q: a spatial
// joint's frame in its second body is read from the design pose (docs/file-format.md "Joints"),
// so a pose that does not hold the joints would change the joints themselves.
void verify_spatial(const Model& back, const std::string& origin, const Model& model, const VecX& q,
                    const std::vector<WrittenFrame>& frames, double length_scale) {
  const auto differ = [&](const std::string& what) {
    throw InputError({origin, 1, 1}, "file",
                     "the edited file would not read back as the assembled mechanism (" + what +
                         " differs); nothing was written");
  };
  for (size_t b = 0; b < model.bodies.size(); ++b) {
    const SpatialBodyData &x = model.bodies[b].spatial, &y = back.bodies[b].spatial;
    const std::string name = "body '" + model.bodies[b].name + "'";
    if (x.inertia != y.inertia || x.com_local != y.com_local || x.points != y.points) differ(name);
    const double scale = std::max(1.0, length_scale);
    if (!((y.design_position - frames[b].origin).cwiseAbs().maxCoeff() <= kRoundTrip * scale))
      differ("the position of " + name);
    const Mat3 dR = rotation_matrix(y.design_orientation) - rotation_matrix(frames[b].orientation);
    if (!(dR.cwiseAbs().maxCoeff() <= kRoundTrip)) differ("the orientation of " + name);
  }
  VecX f_model = VecX::Zero(model.nc), f_back = VecX::Zero(back.nc);
  compute_constraint_residual(model, q, f_model);
  compute_constraint_residual(back, back.design_q(), f_back);
  const double allowed = f_model.size() == 0 ? 0.0 : f_model.cwiseAbs().maxCoeff();
  if (f_back.size() != f_model.size() ||
      !(f_back.size() == 0 ||
        f_back.cwiseAbs().maxCoeff() <= allowed + kRoundTrip * std::max(1.0, length_scale)))
    differ("the joint closure at the design pose");
}

// The offset just past the text of a node: a plain scalar's last character, a flow collection's
// closing bracket, a block collection's last entry. Throws (a --write message) when the text is
// not where the parser says (quoted or unusual YAML).
size_t node_end(const std::string& text, const YAML::Node& node, const std::string& origin,
                const std::string& element, int depth = 0) {
  const YAML::Mark m = node.Mark();
  auto cannot = [&] {
    throw InputError({origin, m.line + 1, m.column + 1}, element,
                     "cannot locate the pose in the file text (quoted or unusual YAML); --write "
                     "needs plain numbers");
  };
  if (depth > 50 || m.is_null() || m.pos < 0 || static_cast<size_t>(m.pos) >= text.size()) cannot();
  const auto pos = static_cast<size_t>(m.pos);
  if (node.IsScalar()) {
    const std::string& scalar = node.Scalar();
    if (pos + scalar.size() > text.size() || text.compare(pos, scalar.size(), scalar) != 0)
      cannot();
    return pos + scalar.size();
  }
  if (text[pos] == '{' || text[pos] == '[') {  // the matching bracket; strings and comments skipped
    int open = 0;
    for (size_t i = pos; i < text.size(); ++i) {
      const char c = text[i];
      if (c == '#' &&
          (i == 0 || text[i - 1] == ' ' || text[i - 1] == '\t' || text[i - 1] == '\n')) {
        i = text.find('\n', i);
        if (i == std::string::npos) break;
      } else if (c == '"' || c == '\'') {
        for (++i; i < text.size() && text[i] != c; ++i)
          if (c == '"' && text[i] == '\\') ++i;
      } else if (c == '{' || c == '[') {
        ++open;
      } else if ((c == '}' || c == ']') && --open == 0) {
        return i + 1;
      }
    }
    cannot();
  }
  size_t end = pos;
  if (node.IsSequence())
    for (const auto& item : node)
      end = std::max(end, node_end(text, item, origin, element, depth + 1));
  else if (node.IsMap())
    for (const auto& kv : node) {
      end = std::max(end, node_end(text, kv.first, origin, element, depth + 1));
      if (!kv.second.IsNull())
        end = std::max(end, node_end(text, kv.second, origin, element, depth + 1));
    }
  else
    cannot();
  return end;
}

// Every scalar under `node` is reached once from the root (none shared through an anchor and
// alias: editing it would change the other uses too).
void check_unshared(const YAML::Node& node, const std::map<int, int>& uses,
                    const std::string& origin, const std::string& element, int depth = 0) {
  if (depth > 50) return;
  if (node.IsScalar()) {
    const auto it = uses.find(node.Mark().pos);
    if (it == uses.end() || it->second != 1) {
      const YAML::Mark m = node.Mark();
      throw InputError({origin, m.line + 1, m.column + 1}, element,
                       "the pose is shared with another place through a YAML anchor and alias; "
                       "--write edits numbers in place and would change the other uses too: "
                       "write this pose out in full");
    }
  } else if (node.IsSequence()) {
    for (const auto& item : node) check_unshared(item, uses, origin, element, depth + 1);
  } else if (node.IsMap()) {
    for (const auto& kv : node) {
      check_unshared(kv.first, uses, origin, element, depth + 1);
      check_unshared(kv.second, uses, origin, element, depth + 1);
    }
  }
}

// The text with the edits made (from the last to the first: the offsets stay valid).
std::string apply(const std::string& text, std::vector<Edit> edits) {
  std::sort(edits.begin(), edits.end(),
            [](const Edit& a, const Edit& b) { return a.begin > b.begin; });
  std::string out = text;
  for (const Edit& e : edits) out.replace(e.begin, e.end - e.begin, e.text);
  return out;
}

// "body 'coupler': pose x: the expression 'b/2' is now 41.5 (the assembly moved it)".
std::string expression_note(const std::string& element, const std::string& component,
                            const std::string& expression, const std::string& number) {
  return element + ": pose " + component + ": the expression '" + expression + "' is now " +
         number + " (the assembly moved it)";
}
std::string expression_note(const std::string& element, char component,
                            const std::string& expression, const std::string& number) {
  return expression_note(element, std::string(1, component), expression, number);
}

// The edit that writes `value` over the plain number `v` of the text.
Edit number_edit(const std::string& text, const YAML::Node& v, const std::map<int, int>& uses,
                 const std::string& origin, const std::string& element, double value) {
  const size_t end = node_end(text, v, origin, element);
  if (!v.IsScalar())
    throw InputError({origin, v.Mark().line + 1, v.Mark().column + 1}, element,
                     "the pose has the wrong shape");
  check_unshared(v, uses, origin, element);
  return {static_cast<size_t>(v.Mark().pos), end, written_number(value)};
}

std::string quaternion_text(const Quat& e) {
  return "{quaternion: [" + written_number(e(0)) + ", " + written_number(e(1)) + ", " +
         written_number(e(2)) + ", " + written_number(e(3)) + "]}";
}

// The edits of a spatial file (docs/cli.md "assemble"): each body's `position` numbers in place;
// its orientation as a quaternion, `{quaternion: [e0, e1, e2, e3]}`: the four numbers in place
// when the file gives that form, the whole `orientation` value replaced when it gives another
// (axis–angle, two axes, Euler angles), the key added when it has none. A body whose orientation
// is the one read (bit for bit) keeps its orientation text. The written frames in `frames`.
void spatial_pose_edits(const std::string& text, const YAML::Node& bodies,
                        const std::map<int, int>& uses, const std::string& origin,
                        const Model& model, const VecX& q, double length, std::vector<Edit>& edits,
                        std::vector<WrittenFrame>& frames, std::vector<std::string>& replaced) {
  // Rounding noise as 0 (io/noise.hpp): lengths against the largest coordinate of the mechanism;
  // quaternion components (at most 1) against 1.
  NoiseFloor noise;
  std::vector<WrittenFrame> exact;
  for (const Body& body : model.bodies) {
    const Quat e = q.segment<4>(body.q_offset + 3) / q.segment<4>(body.q_offset + 3).norm();
    const Vec3 r = q.segment<3>(body.q_offset) - rotation_matrix(e) * body.spatial.com_local;
    for (int k = 0; k < 3; ++k) {
      noise.see(Dimension::length, r(k));
      noise.see(Dimension::length, q(body.q_offset + k));
    }
    exact.push_back({r, e});
  }
  const bool crlf = text.find("\r\n") != std::string::npos;
  double length_scale = 0.0;
  for (const WrittenFrame& f : exact)
    length_scale = std::max(length_scale, f.origin.cwiseAbs().maxCoeff());
  for (size_t b = 0; b < model.bodies.size(); ++b) {
    const Body& body = model.bodies[b];
    const std::string element = "body '" + body.name + "'";
    const YAML::Node item = bodies[b];
    const YAML::Node pose = item["pose"];
    const YAML::Node position = pose ? pose["position"] : YAML::Node();
    if (!item["name"] || item["name"].Scalar() != body.name || !pose || !pose.IsMap() ||
        !position || !position.IsSequence() || position.size() != 3)
      throw InputError({origin, 0, 0}, element, "the file does not match the model");
    WrittenFrame frame;
    for (int k = 0; k < 3; ++k) {
      frame.origin(k) = noise.clean(Dimension::length, exact[b].origin(k));
      const YAML::Node v = position[static_cast<size_t>(k)];
      const double before = body.spatial.design_position(k);
      if (keeps_expression(v, before, frame.origin(k), length_scale)) {
        frame.origin(k) = before;
        continue;
      }
      edits.push_back(number_edit(text, v, uses, origin, element, frame.origin(k) / length));
      if (v.IsScalar() && !is_plain_number(v.Scalar()))
        replaced.push_back(expression_note(element, "xyz"[k], v.Scalar(), edits.back().text));
    }
    const Quat& e = exact[b].orientation;
    for (int k = 0; k < 4; ++k)
      frame.orientation(k) = std::abs(e(k)) <= kNoiseRelative ? 0.0 : e(k);
    const YAML::Node o = pose["orientation"];
    const bool unchanged =
        q.segment<4>(body.q_offset + 3) == body.spatial.design_orientation.normalized();
    if (unchanged) {
      frame.orientation = body.spatial.design_orientation;
    } else if (o && o.IsMap() && o["quaternion"]) {
      const YAML::Node v = o["quaternion"];
      if (!v.IsSequence() || v.size() != 4)
        throw InputError({origin, 0, 0}, element, "the file does not match the model");
      for (int k = 0; k < 4; ++k)
        edits.push_back(number_edit(text, v[static_cast<size_t>(k)], uses, origin, element,
                                    frame.orientation(k)));
    } else if (o) {
      check_unshared(o, uses, origin, element);
      const size_t end = node_end(text, o, origin, element);
      edits.push_back({static_cast<size_t>(o.Mark().pos), end, quaternion_text(frame.orientation)});
    } else {  // no orientation (the identity): the key added after the position
      const size_t end = node_end(text, position, origin, element);
      if (text[static_cast<size_t>(pose.Mark().pos)] == '{') {
        edits.push_back({end, end, ", orientation: " + quaternion_text(frame.orientation)});
      } else {  // a block mapping: a line after the position's, at the key's indentation
        size_t eol = text.find('\n', end);
        if (eol == std::string::npos) eol = text.size();
        if (eol > end && text[eol - 1] == '\r') --eol;
        const YAML::Mark key = pose.begin()->first.Mark();
        if (key.column < 0)
          throw InputError({origin, 0, 0}, element, "the file does not match the model");
        edits.push_back({eol, eol,
                         std::string(crlf ? "\r\n" : "\n") +
                             std::string(static_cast<size_t>(key.column), ' ') +
                             "orientation: " + quaternion_text(frame.orientation)});
      }
    }
    frames.push_back(frame);
  }
}

// The file as an edit sees it: the text without a UTF-8 byte order mark (the YAML parser's
// offsets start after it; the mark is put back on the result), its YAML tree, how often each
// node is reached (an alias reaches one twice), and its bodies, checked against the model's.
struct EditedFile {
  bool has_bom = false;
  std::string text;
  YAML::Node root;
  std::map<int, int> uses;
  YAML::Node bodies;
  std::string with_bom(const std::string& out) const { return has_bom ? kBom + out : out; }
  static inline const std::string kBom = "\xEF\xBB\xBF";
};

EditedFile load_edited_file(const std::string& file_text, const std::string& origin,
                            const Model& model) {
  EditedFile f;
  f.has_bom = file_text.rfind(EditedFile::kBom, 0) == 0;
  f.text = f.has_bom ? file_text.substr(EditedFile::kBom.size()) : file_text;
  try {
    f.root = YAML::Load(f.text);
  } catch (const YAML::Exception& e) {
    throw InputError({origin, e.mark.line + 1, e.mark.column + 1}, "YAML", e.msg);
  }
  count_uses(f.root, f.uses);
  f.bodies = f.root["bodies"];
  if (!f.bodies || !f.bodies.IsSequence() || f.bodies.size() != model.bodies.size())
    throw InputError({origin, 0, 0}, "file", "the bodies in the file do not match the model");
  return f;
}

}  // namespace

std::string replace_design_poses(const std::string& file_text, const std::string& origin,
                                 const Model& model, const VecX& q) {
  return edit_design_poses(file_text, origin, model, q).text;
}

PoseEdit edit_design_poses(const std::string& file_text, const std::string& origin,
                           const Model& model, const VecX& q) {
  check_argument(q.size() == model.nq, "edit_design_poses", "q", "must have model.nq coordinates");
  const EditedFile file = load_edited_file(file_text, origin, model);
  const std::string& text = file.text;
  const std::map<int, int>& uses = file.uses;
  const YAML::Node& root = file.root;
  const YAML::Node& bodies = file.bodies;
  std::vector<Vec3> frames;
  const double length = unit_factor(root["units"], "length", origin);
  const double angle = unit_factor(root["units"], "angle", origin);
  // Rounding noise of the assembled pose (a slider's y on a horizontal guide, 1e-18 m; the frame
  // origin of a crank turning about it) is written as 0 (io/noise.hpp): lengths against the
  // largest coordinate of the mechanism, angles against half a turn.
  if (model.dimension == 3) {
    std::vector<WrittenFrame> spatial_frames;
    std::vector<Edit> edits;
    std::vector<std::string> replaced;
    spatial_pose_edits(text, bodies, uses, origin, model, q, length, edits, spatial_frames,
                       replaced);
    const std::string out = apply(text, edits);
    double scale = 0.0;
    for (const WrittenFrame& f : spatial_frames)
      scale = std::max(scale, f.origin.cwiseAbs().maxCoeff());
    verify_spatial(verify_written(out, origin, model, frames), origin, model, q, spatial_frames,
                   scale);
    return {file.with_bom(out), replaced};
  }
  NoiseFloor noise;
  for (const Body& body : model.bodies) {
    noise.see(Dimension::length, q(body.q_offset));
    noise.see(Dimension::length, q(body.q_offset + 1));
    noise.see(Dimension::length, body.com_local.norm());
  }
  // The scales of keeps_expression: verify_written's.
  double length_scale = 0.0;
  for (const Body& body : model.bodies) {
    const double phi = body.kind == BodyKind::rigid ? q(body.q_offset + 2) : 0.0;
    const Vec2 com(std::cos(phi) * body.com_local.x() - std::sin(phi) * body.com_local.y(),
                   std::sin(phi) * body.com_local.x() + std::cos(phi) * body.com_local.y());
    length_scale = std::max({length_scale, std::abs(q(body.q_offset) - com.x()),
                             std::abs(q(body.q_offset + 1) - com.y())});
  }
  std::vector<Edit> edits;
  std::vector<std::string> replaced;
  for (size_t b = 0; b < model.bodies.size(); ++b) {
    const Body& body = model.bodies[b];
    const YAML::Node item = bodies[b];
    const YAML::Node pose = item["pose"];
    if (!item["name"] || item["name"].Scalar() != body.name || !pose || !pose.IsSequence())
      throw InputError({origin, 0, 0}, "body '" + body.name + "'",
                       "the file does not match the model");
    // The body frame: origin = centre of mass − R(φ) com (q holds the centre of mass).
    const double phi = body.kind == BodyKind::rigid ? q(body.q_offset + 2) : 0.0;
    const double c = std::cos(phi), s = std::sin(phi);
    const Vec2 com_world(c * body.com_local.x() - s * body.com_local.y(),
                         s * body.com_local.x() + c * body.com_local.y());
    const Vec2 r(noise.clean(Dimension::length, q(body.q_offset) - com_world.x()),
                 noise.clean(Dimension::length, q(body.q_offset + 1) - com_world.y()));
    std::vector<double> values = {r.x() / length, r.y() / length};
    if (body.kind == BodyKind::rigid) values.push_back(noise.clean(Dimension::angle, phi) / angle);
    frames.emplace_back(r.x(), r.y(), phi);
    if (pose.size() != values.size())
      throw InputError({origin, 0, 0}, "body '" + body.name + "'", "pose has the wrong size");
    for (size_t k = 0; k < values.size(); ++k) {
      const YAML::Node v = pose[k];
      const YAML::Mark m = v.Mark();
      const std::string& scalar = v.Scalar();
      if (m.is_null() || m.pos < 0 || static_cast<size_t>(m.pos) + scalar.size() > text.size() ||
          text.compare(static_cast<size_t>(m.pos), scalar.size(), scalar) != 0)
        throw InputError({origin, m.line + 1, m.column + 1}, "body '" + body.name + "'",
                         "cannot locate the pose numbers in the file text (quoted or unusual "
                         "YAML); --write needs plain numbers");
      if (const auto use = uses.find(m.pos); use == uses.end() || use->second != 1)
        throw InputError({origin, m.line + 1, m.column + 1}, "body '" + body.name + "'",
                         "the pose is shared with another place through a YAML anchor and alias; "
                         "--write edits numbers in place and would change the other uses too: "
                         "write this pose out in full");
      // An expression the assembly did not move keeps its text (and the frame its value).
      const auto i = static_cast<Eigen::Index>(k);
      const double after = k < 2 ? values[k] * length : frames.back()(i);
      const double before = body.design_pose(i);
      if (keeps_expression(v, before, after, k < 2 ? length_scale : std::abs(before))) {
        frames.back()(i) = before;
        continue;
      }
      const size_t begin = static_cast<size_t>(m.pos);
      edits.push_back({begin, begin + scalar.size(), written_number(values[k])});
      if (!is_plain_number(scalar))
        replaced.push_back(expression_note("body '" + body.name + "'",
                                           k == 0   ? "x"
                                           : k == 1 ? "y"
                                                    : "angle",
                                           scalar, edits.back().text));
    }
  }
  const std::string out = apply(text, edits);
  (void)verify_written(out, origin, model, frames);
  return {file.with_bom(out), replaced};
}

namespace {

// The edits of one body's mass properties (edit_mass_properties).
void mass_edits(const std::string& text, const YAML::Node& item, const std::map<int, int>& uses,
                const std::string& origin, const Body& body, const MassEdit& c, const UnitSystem& u,
                std::vector<Edit>& edits) {
  const std::string element = "body '" + body.name + "'";
  auto node = [&](const char* key) {
    const YAML::Node v = item[key];
    if (!v)
      throw InputError(
          {origin, item.Mark().line + 1, item.Mark().column + 1}, element,
          std::string("has no '") + key + "' to edit; write it out (`" + key + ":`) and run again");
    return v;
  };
  edits.push_back(
      number_edit(text, node("mass"), uses, origin, element + ": mass", c.mass / u.mass_si));
  const YAML::Node com = node("com");
  if (!com.IsSequence() || com.size() != 2)
    throw InputError({origin, com.Mark().line + 1, com.Mark().column + 1}, element,
                     "com must be [x, y] to be edited");
  for (int k = 0; k < 2; ++k)
    edits.push_back(number_edit(text, com[static_cast<size_t>(k)], uses, origin, element + ": com",
                                c.com(k) / u.length_si));
  edits.push_back(number_edit(text, node("inertia"), uses, origin, element + ": inertia",
                              c.inertia / (u.mass_si * u.length_si * u.length_si)));
}

}  // namespace

std::string edit_mass_properties(const std::string& file_text, const std::string& origin,
                                 const Model& model, const std::vector<MassEdit>& changes) {
  check_argument(model.dimension == 2, "edit_mass_properties", "model", "must be planar");
  const EditedFile file = load_edited_file(file_text, origin, model);
  const std::string& text = file.text;
  const std::map<int, int>& uses = file.uses;
  const YAML::Node& bodies = file.bodies;
  const UnitSystem u = unit_system(model.units);
  std::vector<Edit> edits;
  for (const MassEdit& c : changes) {
    check_argument(c.body >= 0 && static_cast<size_t>(c.body) < model.bodies.size(),
                   "edit_mass_properties", "changes", "must name bodies of the model");
    const Body& body = model.bodies[static_cast<size_t>(c.body)];
    const YAML::Node item = bodies[static_cast<size_t>(c.body)];
    if (!item["name"] || item["name"].Scalar() != body.name)
      throw InputError({origin, 0, 0}, "body '" + body.name + "'",
                       "the file does not match the model");
    mass_edits(text, item, uses, origin, body, c, u, edits);
  }
  const std::string out = apply(text, edits);
  // Read back: the changed bodies carry the new values (to the 15 digits written), every other
  // body and element is the model's.
  Model back;
  try {
    back = parse_mechanism(out, origin);
  } catch (const InputError& e) {
    throw InputError(
        {origin, 1, 1}, "file",
        "the edited file would not read back (" + e.message() + "); nothing was written");
  }
  // (15 significant digits and a unit conversion each way: 1e-12 relative.)
  auto close = [](double a, double b) {
    return std::abs(a - b) <= 1e-12 * std::max(std::abs(a), std::abs(b));
  };
  bool same =
      back.bodies.size() == model.bodies.size() && back.joints.size() == model.joints.size();
  for (size_t b = 0; same && b < model.bodies.size(); ++b) {
    const Body &x = model.bodies[b], &y = back.bodies[b];
    double mass = x.mass, inertia = x.inertia;
    Vec2 com = x.com_local;
    for (const MassEdit& c : changes)
      if (static_cast<size_t>(c.body) == b) mass = c.mass, inertia = c.inertia, com = c.com;
    same = x.name == y.name && x.points == y.points && close(mass, y.mass) &&
           close(inertia, y.inertia) &&
           (com - y.com_local).norm() <= 1e-12 * (com.norm() + y.com_local.norm()) + 1e-15;
  }
  if (!same)
    throw InputError({origin, 1, 1}, "file",
                     "the edited file would not read back with the new mass properties; nothing "
                     "was written");
  return file.with_bom(out);
}

}  // namespace orthomech
