// `assemble --write` edits the pose numbers in the file text (issue 17, "nothing lost"): for every
// YAML feature the edited text is either re-read (here, by the reader, independently of the
// writer's own check) as exactly the mechanism with the new poses, or refused with a reason and
// nothing written. One test per feature: flow and block style, anchors without and with aliases,
// merge keys, a UTF-8 byte order mark, CRLF line ends; spatial files: every orientation form
// written as a quaternion, an aliased orientation refused.
#include "orthomech/io/mechanism_writer.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "orthomech/error.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "support/cli_runner.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

// A two-link arm, SI units, in the style given by `pose_a` and `pose_b` (the text after `pose:`).
std::string arm(const std::string& pose_a, const std::string& pose_b,
                const std::string& extra = "") {
  return "orthomech: 1\n"
         "bodies:\n"
         "  - name: upper\n"
         "    mass: 1\n"
         "    inertia: 0.1\n"
         "    com: [0.5, 0]\n"
         "    pose: " +
         pose_a +
         "\n"
         "    points: {E: [1, 0]}\n"
         "  - name: fore\n"
         "    mass: 2\n"
         "    inertia: 0.2\n"
         "    pose: " +
         pose_b + "\n" + extra +
         "joints:\n"
         "  - {name: S, type: revolute, connects: [ground.origin, upper.origin]}\n"
         "  - {name: E, type: revolute, connects: [upper.E, fore.origin]}\n";
}

// New design coordinates: every coordinate moved (by 0.1 + k/100, a value that is not short in
// decimal), so every pose number must be rewritten.
VecX moved(const Model& m) {
  VecX q = m.design_q();
  for (Eigen::Index k = 0; k < q.size(); ++k) q(k) += 0.1 + 0.01 * static_cast<double>(k) / 3.0;
  return q;
}

// The writer's output re-read by the reader gives the coordinates asked for. Tolerance: the
// shortest round-trip text in file units (SI here) is exact; the centre of mass adds one
// rotation of com (a few ulps of 1 m).
constexpr double kRoundTrip = 1e-14;

void expect_round_trip(const std::string& text) {
  const Model m = parse_mechanism(text, "arm.yaml");
  const VecX q = moved(m);
  const std::string out = replace_design_poses(text, "arm.yaml", m, q);
  const Model back = parse_mechanism(out, "arm.yaml");
  EXPECT_LE((back.design_q() - q).cwiseAbs().maxCoeff(), kRoundTrip) << out;
  ASSERT_EQ(back.bodies.size(), m.bodies.size());
  for (size_t b = 0; b < m.bodies.size(); ++b) {
    EXPECT_EQ(back.bodies[b].mass, m.bodies[b].mass);
    EXPECT_EQ(back.bodies[b].points, m.bodies[b].points);
  }
}

TEST(MechanismWriter, FlowStylePosesRoundTrip) { expect_round_trip(arm("[0, 0, 0]", "[1, 0, 0]")); }

TEST(MechanismWriter, BlockStylePosesRoundTrip) {
  expect_round_trip(arm("\n      - 0\n      - 0\n      - 0", "\n      - 1\n      - 0\n      - 0"));
}

TEST(MechanismWriter, AnchoredPoseWithoutAliasRoundTrips) {
  expect_round_trip(arm("&a [0, 0, 0]", "&b [1, 0, 0]"));
}

TEST(MechanismWriter, CrlfLineEndsRoundTripAndAreKept) {
  std::string text = arm("[0, 0, 0]", "[1, 0, 0]");
  std::string crlf;
  for (char c : text) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  expect_round_trip(crlf);
  const Model m = parse_mechanism(crlf, "arm.yaml");
  const std::string out = replace_design_poses(crlf, "arm.yaml", m, moved(m));
  EXPECT_EQ(out.find("\n"), out.find("\r\n") + 1);  // the first line end is still CRLF
}

TEST(MechanismWriter, ByteOrderMarkIsKeptAndTheFileRoundTrips) {
  const std::string text = "\xEF\xBB\xBF" + arm("[0, 0, 0]", "[1, 0, 0]");
  expect_round_trip(text);
  const Model m = parse_mechanism(text, "arm.yaml");
  EXPECT_EQ(replace_design_poses(text, "arm.yaml", m, moved(m)).rfind("\xEF\xBB\xBF", 0), 0u);
}

// A pose shared through an alias: one edit would change both bodies (the corrupt file of
// issue 17); refused at the pose, with the reason.
TEST(MechanismWriter, PoseSharedThroughAnAliasIsRefused) {
  const std::string text = arm("&p [0, 0, 0]", "*p");
  const Model m = parse_mechanism(text, "arm.yaml");
  try {
    (void)replace_design_poses(text, "arm.yaml", m, moved(m));
    FAIL() << "an aliased pose was edited";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().line, 7);
    EXPECT_NE(e.message().find("alias"), std::string::npos) << e.message();
  }
}

// A particle's pose reused as a point of another body: editing the pose would move the point.
TEST(MechanismWriter, PoseReusedAsAPointIsRefused) {
  const std::string text =
      "orthomech: 1\n"
      "bodies:\n"
      "  - {name: bob, type: particle, mass: 1, pose: &p [1, 0]}\n"
      "  - {name: bar, mass: 1, inertia: 0.1, pose: [0, 0, 0], points: {B: *p}}\n"
      "joints:\n"
      "  - {name: O, type: revolute, connects: [ground.origin, bar.origin]}\n"
      "  - {name: B, type: revolute, connects: [bar.B, bob.origin]}\n";
  const Model m = parse_mechanism(text, "p.yaml");
  EXPECT_THROW((void)replace_design_poses(text, "p.yaml", m, moved(m)), InputError);
}

// Merge keys are not part of the format: the reader refuses them, so nothing is ever written.
TEST(MechanismWriter, MergeKeysAreRefusedByTheReader) {
  const std::string text = arm("[0, 0, 0]", "[1, 0, 0]") +
                           "loads:\n"
                           "  - &g {name: g1, type: gravity}\n"
                           "  - {<<: *g, name: g2}\n";
  EXPECT_THROW((void)parse_mechanism(text, "m.yaml"), InputError);
}

// Through the command line: `assemble --in-place` on a file with an aliased pose exits 2 with the
// reason printed once ("error:" once), and the input is untouched byte for byte.
TEST(MechanismWriter, InPlaceOnAnAliasedPoseLeavesTheInputUntouched) {
  namespace fs = std::filesystem;
  const fs::path file = fs::temp_directory_path() / "orthomech-writer-alias.yaml";
  // Drawn open so that assembly moves the bodies (the pin E is 0.5 m apart).
  const std::string text = arm("&p [0, 0, 0.5]", "*p");
  std::ofstream(file, std::ios::binary) << text;
  const test::CliResult r = test::run_cli({"assemble", file.string(), "--in-place"});
  const std::string after = test::read_text(file);
  fs::remove(file);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(after, text);
  EXPECT_NE(r.err.find("alias"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("error:"), r.err.rfind("error:")) << r.err;  // one prefix
  EXPECT_EQ(r.out, "");
}

// Poses replaced in the text of a bundled file read back as the positions written, and the
// text around them (a UTF-8 comment first: positions are byte offsets) is kept.
TEST(MechanismWriter, ReplacedPosesReadBackAndCommentsKept) {
  for (const char* name : {"andrews-squeezer", "crank-rocker"}) {
    const std::string path = test::source_path(std::string("mechanisms/") + name + ".yaml");
    std::ifstream in(path);
    std::stringstream text;
    text << in.rdbuf();
    Model m = load_mechanism(path);
    // Move every body (as if assembled elsewhere) and write.
    VecX q = m.design_q();
    for (Eigen::Index i = 0; i < q.size(); ++i) q(i) += 1e-3 * static_cast<double>(i % 5);
    // A UTF-8 comment first: positions in the text are byte offsets.
    const std::string original = "# Grübler — λ, µ\n" + text.str();
    const std::string out = replace_design_poses(original, path, m, q);
    EXPECT_EQ(out.substr(0, 80), original.substr(0, 80));  // header comment kept
    const Model back = parse_mechanism(out, "back");
    const VecX qb = back.design_q();
    EXPECT_LE((qb - q).cwiseAbs().maxCoeff(), 1e-14) << name;
  }
}

// Spatial files (dimension 3): five free bodies, one per orientation form (axis–angle, Euler
// angles in a block mapping, a quaternion, two body axes, none), mm and degrees. Every body is
// moved and turned; the re-read file gives q (the quaternion up to its sign) and every
// orientation is written as a quaternion.
std::string spatial_bodies(const std::string& orientation_a) {
  auto body = [](const std::string& name, const std::string& pose) {
    return "  - name: " + name + "\n    mass: 1\n    inertia: [1, 2, 2]\n    com: [10, 0, 5]\n" +
           "    pose: " + pose + "\n";
  };
  return "orthomech: 1\ndimension: 3\nunits: {length: mm, angle: deg}\nbodies:\n" +
         body("a", "{position: [0, 0, 0], orientation: " + orientation_a + "}") +
         body("b",
              "\n      position: [1, 2, 3]\n      orientation:\n        euler: [10, 20, 30]\n"
              "        sequence: zyx   # kept\n") +
         body("c", "{position: [4, 5, 6], orientation: {quaternion: [1, 0.1, 0.2, 0.3]}}") +
         body("d", "{position: [7, 8, 9], orientation: {x: [0, 1, 0], z: [0, 0, 1]}}") +
         body("e", "\n      position: [1, 1, 1]  # no orientation");
}

VecX turned(const Model& m) {
  VecX q = m.design_q();
  for (const Body& b : m.bodies) {
    const double k = static_cast<double>(b.q_offset) / 7.0;
    q.segment<3>(b.q_offset) += Vec3(0.01 + 0.001 * k, -0.002, 0.003 * k);
    Quat e = q.segment<4>(b.q_offset + 3) + Quat(0.0, 0.1 + 0.01 * k, -0.05, 0.02 * k);
    q.segment<4>(b.q_offset + 3) = e / e.norm();
  }
  return q;
}

TEST(MechanismWriter, SpatialPosesRoundTripWithQuaternionOrientations) {
  const std::string text = spatial_bodies("{axis: [0, 0, 1], angle: 30}");
  const Model m = parse_mechanism(text, "s.yaml");
  const VecX q = turned(m);
  const std::string out = replace_design_poses(text, "s.yaml", m, q);
  const Model back = parse_mechanism(out, "s.yaml");
  const VecX r = back.design_q();
  for (const Body& b : m.bodies) {
    EXPECT_LE((r.segment<3>(b.q_offset) - q.segment<3>(b.q_offset)).cwiseAbs().maxCoeff(), 1e-14)
        << b.name << "\n"
        << out;
    const double dot = r.segment<4>(b.q_offset + 3).dot(q.segment<4>(b.q_offset + 3));
    EXPECT_NEAR(std::abs(dot), 1.0, 1e-14) << b.name << "\n" << out;
  }
  EXPECT_EQ(out.find("axis:"), std::string::npos) << out;
  EXPECT_EQ(out.find("euler"), std::string::npos) << out;
  EXPECT_EQ(out.find("x: [0, 1, 0]"), std::string::npos) << out;
  size_t count = 0;
  for (size_t at = out.find("{quaternion: ["); at != std::string::npos;
       at = out.find("{quaternion: [", at + 1))
    ++count;
  EXPECT_EQ(count, 5u) << out;
  EXPECT_NE(out.find("# kept"), std::string::npos) << out;
  EXPECT_NE(out.find("# no orientation\n      orientation: {quaternion: ["), std::string::npos)
      << out;
  // Unmoved coordinates keep the orientation text (bit for bit the one read).
  const std::string same = replace_design_poses(text, "s.yaml", m, m.design_q());
  EXPECT_NE(same.find("euler: [10, 20, 30]"), std::string::npos) << same;
  EXPECT_EQ(same.find("# no orientation\n      orientation"), std::string::npos) << same;
}

// Pose numbers written as expressions of the parameters keep their text where the new
// coordinates leave them (the oracle: the same file with the moved number written out, read by
// the reader, gives q); the moved one is written as a number and named. With the design
// coordinates themselves the text comes back unchanged.
TEST(MechanismWriter, ExpressionsTheAssemblyDidNotMoveKeepTheirText) {
  const std::string params = "parameters: {L: 1, tilt: 30}\n";
  const std::string text = params + arm("[0, 0, tilt]", "[L*cos(tilt*pi/180), L/2, -tilt]");
  const std::string moved_text = params + arm("[0, 0, tilt]", "[L*cos(tilt*pi/180), L/2, -20]");
  const Model m = parse_mechanism(text, "arm.yaml");
  const VecX q = parse_mechanism(moved_text, "arm.yaml").design_q();
  const PoseEdit edit = edit_design_poses(text, "arm.yaml", m, q);
  EXPECT_EQ(edit.text, moved_text);
  EXPECT_EQ(
      edit.replaced_expressions,
      std::vector<std::string>{
          "body 'fore': pose angle: the expression '-tilt' is now -20 (the assembly moved it)"});
  const PoseEdit same = edit_design_poses(text, "arm.yaml", m, m.design_q());
  EXPECT_EQ(same.text, text);
  EXPECT_TRUE(same.replaced_expressions.empty());
}

TEST(MechanismWriter, SpatialPositionExpressionsTheAssemblyDidNotMoveKeepTheirText) {
  const auto file = [](const std::string& y) {
    return "orthomech: 1\ndimension: 3\nunits: {length: mm, angle: deg}\nparameters: {p: 3}\n"
           "bodies:\n  - name: a\n    mass: 1\n    inertia: [1, 2, 2]\n    com: [10, 0, 5]\n"
           "    pose: {position: [p, " +
           y + ", 2*p], orientation: {axis: [0, 0, 1], angle: p*10}}\n";
  };
  const std::string text = file("2*p");
  const Model m = parse_mechanism(text, "s.yaml");
  const VecX q = parse_mechanism(file("7"), "s.yaml").design_q();
  const PoseEdit edit = edit_design_poses(text, "s.yaml", m, q);
  EXPECT_EQ(edit.text, file("7"));
  EXPECT_EQ(edit.replaced_expressions,
            std::vector<std::string>{
                "body 'a': pose y: the expression '2*p' is now 7 (the assembly moved it)"});
}

// An orientation shared through an alias: replacing it would turn the other body too; refused.
TEST(MechanismWriter, SpatialOrientationSharedThroughAnAliasIsRefused) {
  std::string text = spatial_bodies("&o {axis: [0, 0, 1], angle: 30}");
  const std::string from = "orientation: {quaternion: [1, 0.1, 0.2, 0.3]}";
  text.replace(text.find(from), from.size(), "orientation: *o");
  const Model m = parse_mechanism(text, "s.yaml");
  try {
    (void)replace_design_poses(text, "s.yaml", m, turned(m));
    FAIL() << "an aliased orientation was edited";
  } catch (const InputError& e) {
    EXPECT_NE(e.message().find("alias"), std::string::npos) << e.message();
  }
}

}  // namespace
}  // namespace orthomech
