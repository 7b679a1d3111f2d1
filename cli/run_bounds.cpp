#include "run_bounds.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "orthomech/io/file_writer.hpp"

namespace orthomech::cli {

namespace {

std::atomic<bool> interrupted{false};
std::atomic<int> received{0};
struct sigaction previous_int, previous_term;
std::atomic<bool> progress_shown{false};
bool progress_newlines = false;

// First signal: ask the run to stop (the flag). Second: the temporaries being written removed
// (io/file_writer.hpp), then the default action (the process ends with the signal's status).
extern "C" void on_signal(int signal) {
  if (interrupted.exchange(true)) {
    orthomech::remove_pending_temporaries();
    std::signal(signal, SIG_DFL);
    std::raise(signal);
    return;
  }
  received.store(signal);
}

// Installs on_signal for `signal` unless the process ignores it (started under nohup, or in the
// background of a shell without job control): an ignored signal stays ignored.
void install(int signal, struct sigaction& previous) {
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;
  if (::sigaction(signal, nullptr, &previous) == 0 && previous.sa_handler == SIG_IGN) return;
  ::sigaction(signal, &action, &previous);
}

}  // namespace

InterruptScope::InterruptScope() {
  interrupted.store(false);
  received.store(0);
  install(SIGINT, previous_int);
  install(SIGTERM, previous_term);
}

InterruptScope::~InterruptScope() {
  ::sigaction(SIGINT, &previous_int, nullptr);
  ::sigaction(SIGTERM, &previous_term, nullptr);
}

int InterruptScope::signal_received() { return received.load(); }

RunControl run_control(const std::string& command, double time_limit) {
  RunControl control;
  control.time_limit = time_limit;
  control.interrupt = &interrupted;
  const char* forced = std::getenv("ORTHOMECH_PROGRESS");
  progress_newlines = forced && std::strcmp(forced, "1") == 0;
  const bool shown = spdlog::default_logger() &&
                     spdlog::default_logger()->level() <= spdlog::level::warn &&
                     (progress_newlines || ::isatty(STDERR_FILENO) == 1);
  if (progress_newlines) control.progress_after = 0.0;  // tests and logs: from the start
  if (shown)
    control.progress = [command](double fraction) {
      std::fprintf(stderr, "%s%s: %.0f %%%s", progress_newlines ? "" : "\r", command.c_str(),
                   100.0 * fraction, progress_newlines ? "\n" : "");
      std::fflush(stderr);
      progress_shown.store(true);
    };
  return control;
}

void end_progress() {
  if (progress_shown.exchange(false) && !progress_newlines) {
    std::fputs("\r\033[K", stderr);
    std::fflush(stderr);
  }
}

}  // namespace orthomech::cli
