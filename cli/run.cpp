// orthomech's command line: parses it, dispatches to one subcommand, and maps every error to a
// documented exit code (docs/cli.md). Results go to stdout, logs to stderr. The executable
// (cli/main.cpp) and the Python module (python/module.cpp) both run this.
#include "run.hpp"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <iostream>

#include "commands.hpp"
#include "common.hpp"
#include "orthomech/error.hpp"
#include "orthomech/projection/workspace.hpp"
#include "orthomech_git_revision.hpp"

namespace orthomech::cli {

int run(int argc, const char* const* argv) {
  CLI::App app{"orthomech: analysis of planar linkages with the mass-orthogonal projection method"};
  app.set_version_flag("--version", ORTHOMECH_VERSION_LINE);
  app.require_subcommand(1);
  GlobalOptions globals;
  app.add_flag("-q,--quiet", globals.quiet, "only errors on stderr");
  app.add_flag("-v,--verbose", globals.verbose, "debug messages on stderr");
  int exit_code = kOk;
  register_info(app, globals, exit_code);
  register_cycle(app, globals, exit_code);
  register_assemble(app, globals, exit_code);
  register_validate(app, globals, exit_code);
  register_simulate(app, globals, exit_code);
  register_crosscheck(app, globals, exit_code);
  register_render(app, globals, exit_code);
  register_sweep(app, globals, exit_code);
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
  } catch (const std::exception& e) {
    std::cerr << "orthomech: internal error: " << e.what() << '\n';
    return kInternal;
  }
  return exit_code;
}

}  // namespace orthomech::cli
