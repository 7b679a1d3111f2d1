// orthomech: command-line entry (the command line itself is cli/run.cpp).
#include "run.hpp"

int main(int argc, char** argv) { return orthomech::cli::run(argc, argv); }
