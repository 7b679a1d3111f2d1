#include "orthomech/io/mechanism_writer.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <filesystem>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "orthomech/error.hpp"

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

std::string shortest_exact(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);  // shortest round-trip form
  return std::string(buf, r.ptr);
}

struct Edit {
  size_t begin, end;
  std::string text;
};

}  // namespace

std::string replace_design_poses(const std::string& text, const std::string& origin,
                                 const Model& model, const VecX& q) {
  if (q.size() != model.nq) throw std::invalid_argument("replace_design_poses: q size");
  const YAML::Node root = YAML::Load(text);
  const double length = unit_factor(root["units"], "length", origin);
  const double angle = unit_factor(root["units"], "angle", origin);
  const YAML::Node bodies = root["bodies"];
  if (!bodies || !bodies.IsSequence() || bodies.size() != model.bodies.size())
    throw InputError({origin, 0, 0}, "file", "the bodies in the file do not match the model");
  std::vector<Edit> edits;
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
    const Vec2 r(q(body.q_offset) - com_world.x(), q(body.q_offset + 1) - com_world.y());
    std::vector<double> values = {r.x() / length, r.y() / length};
    if (body.kind == BodyKind::rigid) values.push_back(phi / angle);
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
      const size_t begin = static_cast<size_t>(m.pos);
      edits.push_back({begin, begin + scalar.size(), shortest_exact(values[k])});
    }
  }
  std::sort(edits.begin(), edits.end(),
            [](const Edit& a, const Edit& b) { return a.begin > b.begin; });
  std::string out = text;
  for (const Edit& e : edits) out.replace(e.begin, e.end - e.begin, e.text);
  return out;
}

void write_file_atomically(const std::string& path, const std::string& text) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::string leaf(".");
  leaf.append(target.filename().string());
  leaf.append(".tmp-XXXXXX");
  const std::string tmpl = (dir / leaf).string();
  std::vector<char> name(tmpl.begin(), tmpl.end());
  name.push_back('\0');
  const int fd = ::mkstemp(name.data());
  if (fd < 0) throw std::runtime_error("cannot write '" + path + "': " + std::strerror(errno));
  const std::string tmp(name.data());
  auto fail = [&](const std::string& what) {
    const int err = errno;
    ::close(fd);
    ::unlink(tmp.c_str());
    throw std::runtime_error("cannot write '" + path + "': " + what + ": " + std::strerror(err));
  };
  size_t done = 0;
  while (done < text.size()) {
    const ssize_t w = ::write(fd, text.data() + done, text.size() - done);
    if (w < 0) {
      if (errno == EINTR) continue;
      fail("write");
    }
    done += static_cast<size_t>(w);
  }
  if (::fsync(fd) != 0) fail("fsync");
  // Keep the permissions of the file being replaced (mkstemp creates 0600).
  std::error_code ec;
  const auto st = fs::status(target, ec);
  const auto mode = !ec && fs::exists(st) ? static_cast<mode_t>(st.permissions()) : 0644;
  if (::fchmod(fd, mode) != 0) {
    // not fatal: the file keeps mkstemp's 0600
  }
  if (::close(fd) != 0) {
    ::unlink(tmp.c_str());
    throw std::runtime_error("cannot write '" + path + "': close: " + std::strerror(errno));
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    throw std::runtime_error("cannot write '" + path + "': rename: " + std::strerror(err));
  }
}

}  // namespace orthomech
