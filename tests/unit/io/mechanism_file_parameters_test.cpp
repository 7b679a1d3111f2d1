// The file's `parameters:` (named design variables, expressions of them in any number) and
// `--set PATH=VALUE` changes (docs/file-format.md "Parameters", docs/cli.md "Changing the file
// from the command line"). The oracle of every value is the same file written out by hand: a
// parameterised or changed file must read to exactly the model of its hand-edited twin.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "orthomech/error.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

// Replaces the one occurrence of `from` (the test fails if there is not exactly one).
std::string edit(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at == std::string::npos) return text;
  EXPECT_EQ(text.find(from, at + 1), std::string::npos) << from << " appears twice";
  return text.replace(at, from.size(), to);
}

std::string crank_rocker() { return test::read_text(test::bundled_file("crank-rocker")); }

// The crank-rocker with its crank length a and coupler length b as parameters: every point and
// centre of mass that depends on them written as an expression.
std::string parameterised(const std::string& a, const std::string& b) {
  std::string text = crank_rocker();
  text = edit(text, "units: {length: mm",
              "parameters: {a: " + a + ", b: " + b + ", half_b: b / 2}\nunits: {length: mm");
  text = edit(text, "com: [15, 0]", "com: [a/2, 0]");
  text = edit(text, "points: {A0: [0, 0], A: [30, 0]}", "points: {A0: [0, 0], A: [a, 0]}");
  text = edit(text, "com: [40, 0]", "com: [half_b, 0]");
  text = edit(text, "B: [80, 0], P: [40, 20]}", "B: [b, 0], P: [half_b, 20]}");
  return text;
}

// Exact equality of what a parameter or a --set can change.
void expect_same_model(const Model& a, const Model& b) {
  ASSERT_EQ(a.bodies.size(), b.bodies.size());
  for (size_t i = 0; i < a.bodies.size(); ++i) {
    const Body& x = a.bodies[i];
    const Body& y = b.bodies[i];
    SCOPED_TRACE(x.name);
    EXPECT_EQ(x.mass, y.mass);
    EXPECT_EQ(x.inertia, y.inertia);
    EXPECT_EQ(x.com_local, y.com_local);
    EXPECT_EQ(x.design_pose, y.design_pose);
    ASSERT_EQ(x.points.size(), y.points.size());
    for (size_t k = 0; k < x.points.size(); ++k) {
      EXPECT_EQ(x.points[k].first, y.points[k].first);
      EXPECT_EQ(x.points[k].second, y.points[k].second) << x.points[k].first;
    }
  }
  ASSERT_EQ(a.drivers.size(), b.drivers.size());
  for (size_t i = 0; i < a.drivers.size(); ++i) EXPECT_EQ(a.drivers[i].speed, b.drivers[i].speed);
  EXPECT_EQ(a.n, b.n);
  EXPECT_EQ(a.nc, b.nc);
}

TEST(Parameters, ExpressionsReadAsTheLiteralFile) {
  const Model literal = parse_mechanism(crank_rocker(), "literal");
  const Model with_parameters = parse_mechanism(parameterised("30", "80"), "parameterised");
  expect_same_model(with_parameters, literal);
  // Expressions of earlier parameters and built-in functions: 30 = sqrt(18^2 + 24^2).
  expect_same_model(parse_mechanism(parameterised("sqrt(18^2 + 24^2)", "80"), "p"), literal);
}

TEST(Parameters, OneChangeMovesEveryPointThatUsesIt) {
  // The hand-edited twin: crank 35 mm, coupler 84 mm (its com and P at 42).
  std::string twin = crank_rocker();
  twin = edit(twin, "com: [15, 0]", "com: [17.5, 0]");
  twin = edit(twin, "A: [30, 0]}", "A: [35, 0]}");
  twin = edit(twin, "com: [40, 0]", "com: [42, 0]");
  twin = edit(twin, "B: [80, 0], P: [40, 20]}", "B: [84, 0], P: [42, 20]}");
  const Model expected = parse_mechanism(twin, "twin");
  expect_same_model(parse_mechanism(parameterised("35", "84"), "p"), expected);
  // The same through --set: by the parameter's name and by its full path.
  expect_same_model(parse_mechanism(parameterised("30", "80"), "p", {{"a", "35"}, {"b", "84"}}),
                    expected);
  expect_same_model(
      parse_mechanism(parameterised("30", "80"), "p", {{"parameters.a", "35"}, {"b", "2*42"}}),
      expected);
}

TEST(Parameters, SpeedsAndRatesTakeExpressions) {
  // 300 rpm = 1800 deg/s in the file's units.
  const Model literal = parse_mechanism(crank_rocker(), "literal");
  std::string text =
      edit(crank_rocker(), "units: {length: mm", "parameters: {w: 900}\nunits: {length: mm");
  text = edit(text, "speed: 300 rpm", "speed: 2*w");
  EXPECT_EQ(parse_mechanism(text, "p").drivers[0].speed, literal.drivers[0].speed);
}

TEST(Parameters, ErrorsNameTheParameterAndTheField) {
  const auto message = [](const std::string& text) -> std::string {
    try {
      (void)parse_mechanism(text, "p.yaml");
    } catch (const InputError& e) {
      return e.what();
    }
    return "(accepted)";
  };
  const std::string unknown = message(edit(parameterised("30", "80"), "[a/2, 0]", "[c/2, 0]"));
  EXPECT_NE(unknown.find("'c' is not a parameter (parameters: a, b, half_b)"), std::string::npos)
      << unknown;
  EXPECT_NE(unknown.find("body 'crank'"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("p.yaml:"), std::string::npos) << unknown;
  // Without parameters a word keeps the plain message.
  const std::string word = message(edit(crank_rocker(), "mass: 0.03", "mass: heavy"));
  EXPECT_NE(word.find("must be a number, got 'heavy'"), std::string::npos) << word;
  // Division by zero is not finite; a parameter cannot shadow a function; order matters.
  const std::string infinite = message(parameterised("30", "80 / 0"));
  EXPECT_NE(infinite.find("must be finite"), std::string::npos) << infinite;
  const std::string shadow = message(edit(parameterised("30", "80"), "half_b: b / 2", "sin: 1"));
  EXPECT_NE(shadow.find("'sin' is the name of a built-in function"), std::string::npos) << shadow;
  const std::string order = message(edit(parameterised("30", "80"), "{a: 30", "{c: a, a: 30"));
  EXPECT_NE(order.find("parameter 'c': 'a' is not a parameter declared above this one"),
            std::string::npos)
      << order;
}

TEST(FileChanges, PathsReachMapsAndListItemsByNameOrIndex) {
  const std::string text = crank_rocker();
  // Hand-edited twin: crank mass 0.05, coupler point P at [45, 25], driver at 600 rpm.
  std::string twin = edit(text, "mass: 0.03", "mass: 0.05");
  twin = edit(twin, "P: [40, 20]}", "P: [45, 25]}");
  twin = edit(twin, "speed: 300 rpm", "speed: 600 rpm");
  const Model expected = parse_mechanism(twin, "twin");
  expect_same_model(parse_mechanism(text, "c",
                                    {{"bodies.crank.mass", "0.05"},
                                     {"bodies.coupler.points.P", "[45, 25]"},
                                     {"drivers.motor.speed", "600rpm"}}),
                    expected);
  expect_same_model(parse_mechanism(text, "c",
                                    {{"bodies.0.mass", "0.05"},
                                     {"bodies.1.points.P", "[45,25]"},
                                     {"drivers.0.speed", "600 rpm"}}),
                    expected);
  // The later of two changes of one element wins.
  expect_same_model(
      parse_mechanism(twin, "c", {{"bodies.crank.mass", "1"}, {"bodies.crank.mass", "0.05"}}),
      expected);
}

TEST(FileChanges, ProblemsNameTheSetAndTheElement) {
  const std::string text = crank_rocker();
  const auto error = [&](const FileChange& change) -> InputError {
    try {
      (void)parse_mechanism(text, "crank.yaml", {change});
    } catch (const InputError& e) {
      return e;
    }
    ADD_FAILURE() << change.path << " accepted";
    return InputError({}, "", "");
  };
  // Validated exactly as the file: a negative mass is refused, at the --set, naming the body.
  const InputError mass = error({"bodies.crank.mass", "-1"});
  EXPECT_EQ(mass.where().file, "crank.yaml: --set bodies.crank.mass=-1");
  EXPECT_EQ(mass.where().line, 0);
  EXPECT_EQ(mass.element(), "body 'crank'");
  EXPECT_NE(mass.message().find("mass must be positive"), std::string::npos) << mass.what();
  // An item inside a written list is also reported at the --set.
  const InputError point = error({"bodies.coupler.points.P", "[45, abc]"});
  EXPECT_EQ(point.where().file, "crank.yaml: --set bodies.coupler.points.P=[45, abc]");
  // Unknown names list what there is.
  const InputError body = error({"bodies.crnk.mass", "1"});
  EXPECT_EQ(body.element(), "bodies.crnk");
  EXPECT_NE(body.message().find("(names: crank, coupler, rocker)"), std::string::npos)
      << body.what();
  const InputError key = error({"drivers.motor.sped.x", "1"});
  EXPECT_NE(key.message().find("no key 'sped'"), std::string::npos) << key.what();
  // A new key only at the end, where the reader then checks it like any key of the file.
  const InputError typo = error({"drivers.motor.sped", "600rpm"});
  EXPECT_NE(typo.message().find("unknown key 'sped'"), std::string::npos) << typo.what();
  EXPECT_EQ(typo.where().file, "crank.yaml: --set drivers.motor.sped=600rpm");
  const InputError into = error({"name.x", "1"});
  EXPECT_NE(into.message().find("is a single value"), std::string::npos) << into.what();
  const InputError yaml = error({"bodies.crank.mass", "[1, 2"});
  EXPECT_NE(yaml.message().find("not valid YAML"), std::string::npos) << yaml.what();
  EXPECT_THROW((void)parse_file_change("mass"), std::invalid_argument);
  EXPECT_THROW((void)parse_file_change("=1"), std::invalid_argument);
  EXPECT_THROW((void)parse_file_change("a="), std::invalid_argument);
  EXPECT_EQ(parse_file_change("a.b=c=d").value, "c=d");
}

}  // namespace
}  // namespace orthomech
