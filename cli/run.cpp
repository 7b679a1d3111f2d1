// orthomech's command line: parses it, dispatches to one subcommand, and maps every error to a
// documented exit code (docs/cli.md). Results go to stdout, logs to stderr. The executable
// (cli/main.cpp) and the Python module (python/module.cpp) both run this.
#include "run.hpp"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <iostream>
#include <new>
#include <string_view>

#include "commands.hpp"
#include "common.hpp"
#include "orthomech/error.hpp"
#include "orthomech/projection/workspace.hpp"
#include "orthomech_git_revision.hpp"

namespace orthomech::cli {

namespace {

using Register = void (*)(CLI::App&, const GlobalOptions&, int&);
struct Command {
  const char* name;
  Register add;
};
// Every subcommand, in the order `orthomech --help` lists them.
constexpr Command kCommands[] = {
    {"info", register_info},         {"cycle", register_cycle},
    {"assemble", register_assemble}, {"validate", register_validate},
    {"simulate", register_simulate}, {"crosscheck", register_crosscheck},
    {"render", register_render},     {"sweep", register_sweep},
    {"optimize", register_optimize}, {"synthesize", register_synthesize},
    {"balance", register_balance}};

// The subcommand the command line names (its first word after the global flags -q, -v), or
// nullptr when it names none of them (help, version, a mistyped command: every subcommand is
// registered then, for CLI11's listing and messages).
const Command* named_command(int argc, const char* const* argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string_view word = argv[i];
    if (word == "-q" || word == "--quiet" || word == "-v" || word == "--verbose") continue;
    for (const Command& c : kCommands)
      if (word == c.name) return &c;
    return nullptr;
  }
  return nullptr;
}

}  // namespace

int run(int argc, const char* const* argv) {
  CLI::App app{"orthomech: analysis of planar linkages with the mass-orthogonal projection method"};
  app.set_version_flag("--version", ORTHOMECH_VERSION_LINE);
  app.require_subcommand(1);
  GlobalOptions globals;
  app.add_flag("-q,--quiet", globals.quiet, "only errors on stderr");
  app.add_flag("-v,--verbose", globals.verbose, "debug messages on stderr");
  int exit_code = kOk;
  // Only the subcommand that runs is registered: the others' options (a few hundred CLI11
  // objects) cost every start about 0.2 ms (docs/performance.md, "Andrews' squeezer: the start").
  if (const Command* c = named_command(argc, argv))
    c->add(app, globals, exit_code);
  else
    for (const Command& each : kCommands) each.add(app, globals, exit_code);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kBadInput;
  } catch (const orthomech::InputError& e) {
    std::fflush(stdout);
    std::cerr << e.what() << '\n';
    return kBadInput;
  } catch (const orthomech::ModelTooLarge& e) {  // for a command's dense matrices (workspace.hpp)
    std::fflush(stdout);
    std::cerr << "orthomech: " << e.what() << '\n';
    return kBadInput;
  } catch (const std::bad_alloc&) {  // the memory the process may use (ulimit -v, the machine)
    std::fflush(stdout);
    std::cerr << "orthomech: out of memory: the model or the request needs more memory than "
                 "this process may use (ulimit -v, the machine's memory); docs/cli.md \"Limits "
                 "and budgets\"\n";
    return kBadInput;
  } catch (const std::exception& e) {
    std::cerr << "orthomech: internal error: " << e.what() << '\n';
    return kInternal;
  }
  return exit_code;
}

}  // namespace orthomech::cli
