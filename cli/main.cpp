// orthomech: command-line entry (the command line itself is cli/run.cpp). It installs the
// process's signal handlers; during a bounded run (`simulate`, `sweep`) cli/run_bounds.hpp's
// InterruptScope replaces the SIGINT/SIGTERM ones by a clean stop, and restores these after.
#include <csignal>

#include "orthomech/io/file_writer.hpp"
#include "run.hpp"

namespace {

// SIGINT, SIGTERM, SIGHUP: the temporary files being written are removed, then the signal is
// raised again with its default action (SA_RESETHAND restored it on entry; it is delivered when
// the handler returns), so that the exit status is the signal's.
extern "C" void on_termination_signal(int sig) {
  orthomech::remove_pending_temporaries();
  (void)std::raise(sig);
}

void install_termination_handlers() {
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction old {};
    if (::sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;  // nohup
    struct sigaction sa {};
    sa.sa_handler = on_termination_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESETHAND;
    (void)::sigaction(sig, &sa, nullptr);
  }
}

}  // namespace

int main(int argc, char** argv) {
  install_termination_handlers();
  return orthomech::cli::run(argc, argv);
}
