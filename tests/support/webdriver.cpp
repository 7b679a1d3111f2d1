#include "support/webdriver.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <thread>

namespace orthomech::test {

namespace fs = std::filesystem;

namespace {

// A port that was free a moment ago (bind to 0, read it back, close).
int free_port() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return 0;
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = 0;
  socklen_t len = sizeof a;
  int port = 0;
  if (bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 &&
      getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) == 0)
    port = ntohs(a.sin_port);
  close(fd);
  return port;
}

// The body of a chunked HTTP response.
std::string dechunk(const std::string& body) {
  std::string out;
  size_t at = 0;
  while (at < body.size()) {
    const size_t eol = body.find("\r\n", at);
    if (eol == std::string::npos) break;
    const size_t size = std::stoul(body.substr(at, eol - at), nullptr, 16);
    if (size == 0) break;
    out += body.substr(eol + 2, size);
    at = eol + 2 + size + 2;
  }
  return out;
}

// One HTTP/1.1 request to 127.0.0.1:port ("Connection: close"), the response body. Throws
// std::runtime_error when the server cannot be reached or does not answer within 60 s.
std::string http(int port, const std::string& method, const std::string& path,
                 const std::string& body) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) throw std::runtime_error("socket: " + std::string(std::strerror(errno)));
  timeval timeout{60, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &timeout, sizeof timeout);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(static_cast<uint16_t>(port));
  if (connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    const std::string why = std::strerror(errno);
    close(fd);
    throw std::runtime_error("cannot connect to chromedriver: " + why);
  }
  const std::string request = method + " " + path +
                              " HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) +
                              "\r\nContent-Type: application/json; charset=utf-8\r\n"
                              "Content-Length: " +
                              std::to_string(body.size()) + "\r\nConnection: close\r\n\r\n" + body;
  for (size_t sent = 0; sent < request.size();) {
    const ssize_t k = send(fd, request.data() + sent, request.size() - sent, MSG_NOSIGNAL);
    if (k <= 0) {
      close(fd);
      throw std::runtime_error("cannot send to chromedriver");
    }
    sent += static_cast<size_t>(k);
  }
  // Read until the body is complete (Content-Length, or the last chunk), or the server closes:
  // chromedriver may keep the connection open whatever "Connection: close" says.
  std::string response, headers;
  size_t head = std::string::npos, length = std::string::npos;
  bool chunked = false;
  char buf[65536];
  for (;;) {
    if (head == std::string::npos && (head = response.find("\r\n\r\n")) != std::string::npos) {
      headers = response.substr(0, head);
      for (char& c : headers) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      chunked = headers.find("transfer-encoding: chunked") != std::string::npos;
      const size_t at = headers.find("content-length:");
      if (at != std::string::npos) length = std::stoul(headers.substr(at + 15));
    }
    if (head != std::string::npos) {
      const size_t received = response.size() - head - 4;
      if (length != std::string::npos && received >= length) break;
      if (chunked && response.size() >= 5 &&
          response.compare(response.size() - 5, 5, "0\r\n\r\n") == 0)
        break;
    }
    const ssize_t k = recv(fd, buf, sizeof buf, 0);
    if (k < 0) {
      close(fd);
      throw std::runtime_error("no answer from chromedriver to " + method + " " + path);
    }
    if (k == 0) break;
    response.append(buf, static_cast<size_t>(k));
  }
  close(fd);
  if (head == std::string::npos) throw std::runtime_error("bad HTTP answer from chromedriver");
  std::string content = response.substr(head + 4);
  if (chunked) content = dechunk(content);
  return content;
}

}  // namespace

std::string find_program(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/bin:/bin";
  size_t at = 0;
  while (at <= dirs.size()) {
    const size_t colon = dirs.find(':', at);
    const std::string dir =
        dirs.substr(at, colon == std::string::npos ? std::string::npos : colon - at);
    const fs::path candidate = fs::path(dir.empty() ? "." : dir) / name;
    if (access(candidate.c_str(), X_OK) == 0) return candidate.string();
    if (colon == std::string::npos) break;
    at = colon + 1;
  }
  return "";
}

std::string base64_decode(const std::string& text) {
  auto value = [](char c) -> int {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
  };
  std::string out;
  unsigned bits = 0;
  int count = 0;
  for (const char c : text) {
    const int v = value(c);
    if (v < 0) continue;  // '=' padding, line breaks
    bits = (bits << 6) | static_cast<unsigned>(v);
    count += 6;
    if (count >= 8) {
      count -= 8;
      out += static_cast<char>((bits >> count) & 0xffu);
    }
  }
  return out;
}

Browser::Browser(int width, int height) {
  const std::string chromium = find_program("chromium");
  const std::string driver = find_program("chromedriver");
  if (chromium.empty() || driver.empty()) {
    error = std::string(chromium.empty() ? "chromium" : "chromedriver") +
            " is not installed (not on PATH): the browser tests need the Debian packages "
            "chromium and chromium-driver; scripts/setup installs them";
    return;
  }
  static int counter = 0;
  dir_ = fs::temp_directory_path() /
         ("orthomech_browser_" + std::to_string(getpid()) + "_" + std::to_string(counter++));
  fs::create_directories(dir_);
  port_ = free_port();
  const std::string port_arg = "--port=" + std::to_string(port_);
  const std::string log = (dir_ / "chromedriver.log").string();
  driver_ = fork();
  if (driver_ == 0) {
    const int null_fd = open("/dev/null", O_RDWR);
    const int log_fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (null_fd >= 0) dup2(null_fd, STDIN_FILENO);
    if (log_fd >= 0) {
      dup2(log_fd, STDOUT_FILENO);
      dup2(log_fd, STDERR_FILENO);
    }
    execl(driver.c_str(), driver.c_str(), port_arg.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  if (driver_ < 0) {
    error = "cannot start chromedriver";
    return;
  }
  // Ready when /status says so (a few hundred ms).
  bool ready = false;
  for (int k = 0; k < 100 && !ready; ++k) {
    try {
      ready = nlohmann::json::parse(http(port_, "GET", "/status", ""))["value"]["ready"] == true;
    } catch (const std::exception&) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
  if (!ready) {
    error = "chromedriver did not start (its log: " + log + ")";
    return;
  }
  const nlohmann::json options = {
      {"binary", chromium},
      {"args",
       {"--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
        "--hide-scrollbars", "--force-device-scale-factor=1", "--no-first-run",
        "--user-data-dir=" + (dir_ / "profile").string(),
        "--window-size=" + std::to_string(width) + "," + std::to_string(height)}}};
  const nlohmann::json caps = {{"capabilities",
                                {{"alwaysMatch",
                                  {{"browserName", "chrome"},
                                   {"goog:chromeOptions", options},
                                   {"goog:loggingPrefs", {{"browser", "ALL"}}}}}}}};
  try {
    const nlohmann::json answer =
        nlohmann::json::parse(http(port_, "POST", "/session", caps.dump()));
    if (answer["value"].contains("sessionId")) {
      session_ = answer["value"]["sessionId"];
    } else {
      error = "chromedriver cannot start chromium: " + answer["value"].dump();
    }
  } catch (const std::exception& e) {
    error = std::string("chromedriver cannot start chromium: ") + e.what();
  }
}

Browser::~Browser() {
  if (!session_.empty()) {
    try {
      http(port_, "DELETE", "/session/" + session_, "");
    } catch (const std::exception&) {
    }
  }
  if (driver_ > 0) {
    kill(driver_, SIGTERM);
    int status = 0;
    waitpid(driver_, &status, 0);
  }
  if (!dir_.empty()) {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
}

nlohmann::json Browser::command(const std::string& method, const std::string& path,
                                const nlohmann::json& body) {
  const std::string text = http(port_, method, "/session/" + session_ + path,
                                body.is_null() ? std::string() : body.dump());
  nlohmann::json answer = nlohmann::json::parse(text, nullptr, false);
  if (answer.is_discarded()) throw std::runtime_error("WebDriver " + path + ": " + text);
  if (answer["value"].is_object() && answer["value"].contains("error"))
    throw std::runtime_error("WebDriver " + path + ": " + answer["value"]["error"].dump() + " " +
                             answer["value"].value("message", std::string()));
  return answer["value"];
}

void Browser::navigate(const std::string& url) { command("POST", "/url", {{"url", url}}); }

nlohmann::json Browser::execute(const std::string& script, const nlohmann::json& args) {
  return command("POST", "/execute/sync", {{"script", script}, {"args", args}});
}

bool Browser::wait_for(const std::string& script, double seconds) {
  const auto end = std::chrono::steady_clock::now() +
                   std::chrono::milliseconds(static_cast<int>(1000.0 * seconds));
  do {
    if (execute(script) == true) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  } while (std::chrono::steady_clock::now() < end);
  return false;
}

nlohmann::json Browser::element(const std::string& css) {
  return command("POST", "/element", {{"using", "css selector"}, {"value", css}});
}

std::string Browser::screenshot(const nlohmann::json& element) {
  const std::string id = element.begin().value();
  return base64_decode(command("GET", "/element/" + id + "/screenshot", nullptr));
}

void Browser::actions(const nlohmann::json& sources) {
  command("POST", "/actions", {{"actions", sources}});
  command("DELETE", "/actions", nullptr);
}

nlohmann::json Browser::browser_log() {
  try {
    return command("POST", "/se/log", {{"type", "browser"}});
  } catch (const std::exception&) {
    return nullptr;
  }
}

}  // namespace orthomech::test
