#pragma once
// A tiny WebDriver client for the browser tests (issue 14): Debian's chromedriver started on a
// free port of 127.0.0.1, one headless Chromium session, the W3C WebDriver protocol spoken over
// plain HTTP/1.1 (POSIX sockets, nlohmann::json). No download at test time: chromium and
// chromium-driver are Debian packages that scripts/setup installs. When either is missing the
// Browser is not ok() and `error` says so — the tests fail with that message, never pass silently.
#include <sys/types.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace orthomech::test {

class Browser {
 public:
  // Starts chromedriver and a headless Chromium with a window of width × height CSS px at device
  // scale 1 (a CSS px is an image px in screenshots).
  Browser(int width, int height);
  ~Browser();
  Browser(const Browser&) = delete;
  Browser& operator=(const Browser&) = delete;

  [[nodiscard]] bool ok() const { return !session_.empty(); }
  std::string error;  // why not ok()

  // Each throws std::runtime_error with chromedriver's message when a command fails.
  void navigate(const std::string& url);
  // Runs `script` (a function body; `arguments` are `args`) in the page; its return value.
  nlohmann::json execute(const std::string& script,
                         const nlohmann::json& args = nlohmann::json::array());
  // Polls `script` until it returns true, for at most `seconds`; whether it did.
  bool wait_for(const std::string& script, double seconds);
  // The WebDriver reference of the first element matching `css` (throws when none).
  nlohmann::json element(const std::string& css);
  // The element's screenshot: PNG bytes.
  std::string screenshot(const nlohmann::json& element);
  // W3C actions (a list of input sources), then releases them.
  void actions(const nlohmann::json& sources);
  // The browser's console log entries (chromedriver's log endpoint), or nullopt-like null when
  // the endpoint is not there.
  nlohmann::json browser_log();

 private:
  nlohmann::json command(const std::string& method, const std::string& path,
                         const nlohmann::json& body);
  int port_ = 0;
  pid_t driver_ = -1;
  std::string session_;
  std::filesystem::path dir_;  // chromedriver's log and Chromium's profile
};

// Standard base64 (the screenshots) to bytes.
[[nodiscard]] std::string base64_decode(const std::string& text);
// The first executable named `name` on PATH, or "".
[[nodiscard]] std::string find_program(const std::string& name);

}  // namespace orthomech::test
