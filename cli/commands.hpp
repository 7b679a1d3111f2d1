#pragma once
// One subcommand per file; each registers its options and callback on the app.
namespace CLI {
class App;
}

namespace orthomech::cli {
struct GlobalOptions;
// `orthomech info FILE [--json]`: mobility and structure (cli/info.cpp).
void register_info(CLI::App& app, const GlobalOptions& globals, int& exit_code);
// `orthomech cycle FILE [...]`: driven sweep, drive and joint reactions (cli/cycle.cpp).
void register_cycle(CLI::App& app, const GlobalOptions& globals, int& exit_code);
// `orthomech assemble FILE`: Ipopt projection of the design position (cli/assemble.cpp).
void register_assemble(CLI::App& app, const GlobalOptions& globals, int& exit_code);
// `orthomech validate FILE`: design positions report (cli/validate.cpp).
void register_validate(CLI::App& app, const GlobalOptions& globals, int& exit_code);
// `orthomech simulate FILE --t-end T`: forward dynamics (cli/simulate.cpp).
void register_simulate(CLI::App& app, const GlobalOptions& globals, int& exit_code);
// `orthomech crosscheck FILE [--samples N]`: dual vs primal (cli/crosscheck.cpp).
void register_crosscheck(CLI::App& app, const GlobalOptions& globals, int& exit_code);
// `orthomech render FILE --out X.svg|.png|.pdf`: a drawing of the mechanism (cli/render.cpp).
void register_render(CLI::App& app, const GlobalOptions& globals, int& exit_code);
// `sweep`: a design study of many variants (sweep.cpp).
void register_sweep(CLI::App& app, const GlobalOptions& globals, int& exit_code);
// `synthesize TASK`: four-bars from the motion, path or law wanted, validated (synthesize.cpp).
void register_synthesize(CLI::App& app, const GlobalOptions& globals, int& exit_code);
// `optimize FILE --study OPT`: design variables for the best objective under constraints
// (optimize.cpp).
void register_optimize(CLI::App& app, const GlobalOptions& globals, int& exit_code);
// `balance FILE`: counterweights that cancel or reduce the shaking force (balance.cpp).
void register_balance(CLI::App& app, const GlobalOptions& globals, int& exit_code);
}  // namespace orthomech::cli
