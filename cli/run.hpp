#pragma once
// The command line as a function: cli/main.cpp calls it with its arguments, the Python module
// (python/module.cpp) with a command line it builds.

namespace orthomech::cli {

// Parses `argv` (argv[0] is the program name), runs the subcommand and returns its exit code
// (docs/cli.md): results on std::cout, errors on std::cerr, logs on stderr.
int run(int argc, const char* const* argv);

}  // namespace orthomech::cli
