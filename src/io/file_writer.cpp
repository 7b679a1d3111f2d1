#include "orthomech/io/file_writer.hpp"

#include <fcntl.h>
#include <pthread.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstring>
#include <random>
#include <stdexcept>
#include <streambuf>
#include <string>
#include <vector>

namespace orthomech {

namespace {

// ---- The table of live temporary files -------------------------------------------------------
// A fixed array (no allocation, no lock): a slot is free (0), being filled (1) or holds the path
// of a temporary file that exists (2). remove_pending_temporaries() runs in a signal handler and
// only reads slots in state 2.
constexpr size_t kSlotPath = 4096;  // PATH_MAX on Linux
struct Slot {
  std::atomic<int> state{0};
  std::array<char, kSlotPath> path{};
};
static_assert(std::atomic<int>::is_always_lock_free);
// NOTE: a global, against the house style's "no globals": a signal handler can reach nothing
// else.
std::array<Slot, kMaxPendingTemporaries> g_pending;

// The slot of `path`, or -1 when the table is full or the path too long (the temporary is then
// still removed on failure, only not by a signal handler).
int register_temporary(const std::string& path) {
  if (path.size() >= kSlotPath) return -1;
  for (size_t i = 0; i < g_pending.size(); ++i) {
    int expected = 0;
    if (!g_pending[i].state.compare_exchange_strong(expected, 1)) continue;
    std::memcpy(g_pending[i].path.data(), path.c_str(), path.size() + 1);
    g_pending[i].state.store(2, std::memory_order_release);
    return static_cast<int>(i);
  }
  return -1;
}

void unregister_temporary(int slot) {
  if (slot >= 0) g_pending[static_cast<size_t>(slot)].state.store(0, std::memory_order_release);
}

[[noreturn]] void fail(const std::string& path, const std::string& why) {
  throw std::runtime_error("cannot write '" + path + "': " + why);
}

std::string errno_text(int err) { return std::strerror(err); }

// Follows a chain of symbolic links to the path that is finally written (step 1): a relative
// link target is relative to the link's directory. `st` gets the final target's lstat, `exists`
// false when it does not exist (a new file, or a dangling link's target).
std::filesystem::path resolve(const std::string& shown, const std::filesystem::path& path,
                              struct stat& st, bool& exists) {
  std::filesystem::path p = path;
  for (int hop = 0; hop < 40; ++hop) {  // Linux's limit on links followed (ELOOP)
    if (::lstat(p.c_str(), &st) != 0) {
      if (errno != ENOENT) fail(shown, errno_text(errno));
      exists = false;
      return p;
    }
    if (!S_ISLNK(st.st_mode)) {
      exists = true;
      return p;
    }
    std::vector<char> buf(static_cast<size_t>(st.st_size > 0 ? st.st_size : 255) + 1);
    const ssize_t n = ::readlink(p.c_str(), buf.data(), buf.size());
    if (n < 0) fail(shown, errno_text(errno));
    const std::filesystem::path link(std::string(buf.data(), static_cast<size_t>(n)));
    p = link.is_absolute() ? link : p.parent_path() / link;
  }
  fail(shown, errno_text(ELOOP));
}

// A file descriptor closed when it goes.
struct Fd {
  int fd = -1;
  Fd() = default;
  explicit Fd(int f) : fd(f) {}
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  ~Fd() { reset(); }
  void reset() {
    if (fd >= 0) ::close(fd);
    fd = -1;
  }
};

// write() of all of [data, data + size) at the file offset; false with errno on failure.
bool write_all(int fd, const char* data, size_t size) {
  while (size > 0) {
    const ssize_t w = ::write(fd, data, size);
    if (w < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    data += w;
    size -= static_cast<size_t>(w);
  }
  return true;
}

// pwrite() of all of [data, data + size) at `offset`; false with errno on failure.
bool pwrite_all(int fd, const char* data, size_t size, off_t offset) {
  while (size > 0) {
    const ssize_t w = ::pwrite(fd, data, size, offset);
    if (w < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    data += w;
    size -= static_cast<size_t>(w);
    offset += w;
  }
  return true;
}

// Copies [from, to) of the file `src` to the same offsets of `dst`; false with errno on failure.
bool copy_range(int src, int dst, off_t from, off_t to) {
  std::vector<char> buf(1 << 16);
  while (from < to) {
    const auto want = static_cast<size_t>(std::min<off_t>(to - from, 1 << 16));
    const ssize_t r = ::pread(src, buf.data(), want, from);
    if (r < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    if (r == 0) {
      errno = EIO;  // the staged file is shorter than it was a moment ago
      return false;
    }
    if (!pwrite_all(dst, buf.data(), static_cast<size_t>(r), from)) return false;
    from += r;
  }
  return true;
}

// The buffer of FileWriter::stream(): 64 KiB, written to `fd` when full and by flush(). A write
// error is kept (the first errno) and reported by commit().
class FdBuffer : public std::streambuf {
 public:
  FdBuffer() : buf_(1 << 16) { setp(buf_.data(), buf_.data() + buf_.size()); }
  void attach(int fd) { fd_ = fd; }
  [[nodiscard]] int error() const { return error_; }
  // Writes what is buffered; false when a write failed (now or before).
  bool flush() {
    if (error_ == 0 && pptr() > pbase() &&
        !write_all(fd_, pbase(), static_cast<size_t>(pptr() - pbase())))
      error_ = errno;
    setp(buf_.data(), buf_.data() + buf_.size());
    return error_ == 0;
  }

 protected:
  int_type overflow(int_type c) override {
    if (!flush()) return traits_type::eof();
    if (traits_type::eq_int_type(c, traits_type::eof())) return traits_type::not_eof(c);
    *pptr() = traits_type::to_char_type(c);
    pbump(1);
    return c;
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    if (n > epptr() - pptr() && !flush()) return 0;
    if (n <= epptr() - pptr()) {  // buffered
      std::memcpy(pptr(), s, static_cast<size_t>(n));
      pbump(static_cast<int>(n));
      return n;
    }
    if (!write_all(fd_, s, static_cast<size_t>(n))) {  // larger than the buffer: directly
      error_ = errno;
      return 0;
    }
    return n;
  }
  int sync() override { return flush() ? 0 : -1; }

 private:
  std::vector<char> buf_;
  int fd_ = -1;
  int error_ = 0;
};

// SIGINT, SIGTERM and SIGHUP blocked in this thread while it lives (the in-place overwrite):
// delivered, if they came, when it goes.
class BlockTerminationSignals {
 public:
  BlockTerminationSignals() {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    sigaddset(&set, SIGHUP);
    pthread_sigmask(SIG_BLOCK, &set, &old_);
  }
  ~BlockTerminationSignals() { pthread_sigmask(SIG_SETMASK, &old_, nullptr); }
  BlockTerminationSignals(const BlockTerminationSignals&) = delete;
  BlockTerminationSignals& operator=(const BlockTerminationSignals&) = delete;

 private:
  sigset_t old_;
};

// Back to the old size after a failed extension (the error reported is the one that made it
// fail, not this one's).
void restore_size(int fd, off_t size) {
  if (::ftruncate(fd, size) != 0) {
  }
}

enum class Mode { replace, in_place, device };

}  // namespace

struct FileWriter::Impl {
  std::string shown;             // the path as the caller gave it (messages)
  std::filesystem::path target;  // the resolved target (step 1)
  Mode mode = Mode::replace;
  bool exists = false;  // the target exists (its lstat in st)
  struct stat st {};
  Fd out;           // the temporary (replace, in_place) or the device/FIFO
  Fd target_fd;     // in_place: the target, opened for writing
  std::string tmp;  // the temporary's path ("" for a device)
  int slot = -1;    // its slot in g_pending
  FdBuffer buffer;
  std::ostream stream{&buffer};
  bool committed = false;

  // The temporary file next to the target: ".NAME.tmp-XXXXXX", created exclusively with `perm`
  // (read and write: the in-place mode copies it back)
  // (the umask applies, as to any file a program creates; mkstemp would force 0600).
  void create_temporary(mode_t perm) {
    const std::filesystem::path dir =
        target.has_parent_path() ? target.parent_path() : std::filesystem::path(".");
    std::string leaf = target.filename().string();
    if (leaf.size() > 200) leaf.resize(200);  // the name stays within NAME_MAX (255)
    static constexpr char kChars[] =
        "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789";
    std::random_device seed;
    std::mt19937_64 rng((static_cast<uint64_t>(seed()) << 32) ^ seed() ^
                        static_cast<uint64_t>(::getpid()));
    for (int attempt = 0; attempt < 100; ++attempt) {
      std::string name = "." + leaf + ".tmp-";
      for (int k = 0; k < 6; ++k) name += kChars[rng() % (sizeof kChars - 1)];
      const std::string path = (dir / name).string();
      const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, perm);
      if (fd < 0 && errno == EEXIST) continue;
      if (fd < 0)
        fail(shown,
             "cannot create a temporary file in '" + dir.string() + "': " + errno_text(errno));
      out.fd = fd;
      tmp = path;
      slot = register_temporary(tmp);
      return;
    }
    fail(shown, "cannot create a temporary file in '" + dir.string() + "': " + errno_text(EEXIST));
  }

  void remove_temporary() {
    out.reset();
    if (!tmp.empty()) ::unlink(tmp.c_str());
    unregister_temporary(slot);
    slot = -1;
    tmp.clear();
  }

  // Opens a character device or FIFO for writing into it (step 4). A FIFO is opened
  // non-blocking first: without a reader that is ENXIO at once instead of a wait for one.
  void open_device() {
    const bool fifo = S_ISFIFO(st.st_mode);
    const int fd =
        ::open(target.c_str(), O_WRONLY | O_CLOEXEC | O_NOCTTY | (fifo ? O_NONBLOCK : 0));
    if (fd < 0) {
      if (fifo && errno == ENXIO) fail(shown, "no process is reading the FIFO");
      fail(shown, errno_text(errno));
    }
    out.fd = fd;
    if (fifo) {
      const int flags = ::fcntl(fd, F_GETFL);
      if (flags < 0 || ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) < 0)
        fail(shown, errno_text(errno));
    }
  }

  void commit_replace() {
    if (::fsync(out.fd) != 0) fail(shown, "fsync: " + errno_text(errno));
    if (exists) {
      // The target's owner and group first (chown clears set-user-ID bits), then its mode. Not
      // root, a file of another owner cannot be given away: EPERM is expected and ignored.
      if (::fchown(out.fd, st.st_uid, st.st_gid) != 0 && errno != EPERM)
        fail(shown, "fchown: " + errno_text(errno));
      if (::fchmod(out.fd, st.st_mode & 07777) != 0) fail(shown, "fchmod: " + errno_text(errno));
    }
    const int fd = out.fd;
    out.fd = -1;
    if (::close(fd) != 0) fail(shown, "close: " + errno_text(errno));
    if (::rename(tmp.c_str(), target.c_str()) != 0) fail(shown, "rename: " + errno_text(errno));
    unregister_temporary(slot);
    slot = -1;
    tmp.clear();
    // The rename itself made durable (best effort: some filesystems cannot fsync a directory).
    const std::filesystem::path dir =
        target.has_parent_path() ? target.parent_path() : std::filesystem::path(".");
    const Fd d(::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
    if (d.fd >= 0) (void)::fsync(d.fd);
  }

  // Step 3: the staged bytes copied over the target's own inode.
  void commit_in_place() {
    struct stat staged {
    }, now{};
    if (::fstat(out.fd, &staged) != 0 || ::fstat(target_fd.fd, &now) != 0)
      fail(shown, errno_text(errno));
    const off_t size = staged.st_size, old_size = now.st_size;
    const BlockTerminationSignals blocked;
    // (a) Reserve the new size. posix_fallocate returns its error (it does not set errno).
    if (size > 0) {
      const int r = ::posix_fallocate(target_fd.fd, 0, size);
      const bool unsupported = r == EOPNOTSUPP || r == EINVAL || r == ENOSYS;
      if (r != 0 && !unsupported) {
        restore_size(target_fd.fd, old_size);  // undo a partial extension
        fail(shown, errno_text(r));
      }
      // (b) Where the filesystem cannot reserve, the bytes beyond the old end are written first:
      // the old bytes are still all there when that fails.
      if (unsupported && size > old_size && !copy_range(out.fd, target_fd.fd, old_size, size)) {
        const int err = errno;
        restore_size(target_fd.fd, old_size);
        fail(shown, errno_text(err));
      }
    }
    // (c) Overwrite from offset 0, cut to the new size, make it durable.
    const auto partly = [&](const char* what) {
      fail(shown,
           std::string(what) + ": " + errno_text(errno) + " (the file may be partly overwritten)");
    };
    if (!copy_range(out.fd, target_fd.fd, 0, size)) partly("write");
    if (::ftruncate(target_fd.fd, size) != 0) partly("ftruncate");
    if (::fsync(target_fd.fd) != 0) partly("fsync");
    const int fd = target_fd.fd;
    target_fd.fd = -1;
    if (::close(fd) != 0) partly("close");
  }
};

FileWriter::FileWriter(const std::filesystem::path& path) : impl_(std::make_unique<Impl>()) {
  Impl& w = *impl_;
  w.shown = path.string();
  // What the path finally names (stat follows every link, /proc's /dev/stdout too): a device, a
  // FIFO and what is refused are opened or named through the path itself; a regular file is
  // found by following the links one by one (its directory holds the temporary file).
  struct stat followed {};
  if (::stat(path.c_str(), &followed) != 0) {
    if (errno != ENOENT) fail(w.shown, errno_text(errno));
    w.target = resolve(w.shown, path, w.st, w.exists);  // new, or a dangling link's target
  } else if (!S_ISREG(followed.st_mode)) {
    w.target = path;
    w.st = followed;
    w.exists = true;
  } else {
    w.target = resolve(w.shown, path, w.st, w.exists);
    if (!w.exists || w.st.st_dev != followed.st_dev || w.st.st_ino != followed.st_ino)
      fail(w.shown, "its symbolic links do not lead to a path of the file");
  }
  if (!w.exists) {
    w.create_temporary(0666);
  } else if (S_ISREG(w.st.st_mode) && w.st.st_nlink > 1) {
    w.mode = Mode::in_place;
    w.target_fd.fd = ::open(w.target.c_str(), O_WRONLY | O_CLOEXEC);
    if (w.target_fd.fd < 0) fail(w.shown, errno_text(errno));
    w.create_temporary(0600);  // the staging file, removed at the end
  } else if (S_ISREG(w.st.st_mode)) {
    w.create_temporary(0600);  // given the target's mode at commit
  } else if (S_ISCHR(w.st.st_mode) || S_ISFIFO(w.st.st_mode)) {
    w.mode = Mode::device;
    w.open_device();
  } else {
    fail(w.shown, S_ISDIR(w.st.st_mode)    ? "it is a directory"
                  : S_ISSOCK(w.st.st_mode) ? "it is a socket"
                  : S_ISBLK(w.st.st_mode)  ? "it is a block device"
                                           : "it is not a regular file");
  }
  w.buffer.attach(w.out.fd);
}

FileWriter::~FileWriter() {
  if (impl_->committed) return;
  impl_->target_fd.reset();
  impl_->remove_temporary();
}

std::ostream& FileWriter::stream() { return impl_->stream; }

void FileWriter::commit() {
  Impl& w = *impl_;
  if (w.committed) throw std::logic_error("FileWriter::commit called twice");
  try {
    if (!w.buffer.flush()) fail(w.shown, errno_text(w.buffer.error()));
    switch (w.mode) {
      case Mode::replace:
        w.commit_replace();
        break;
      case Mode::in_place:
        w.commit_in_place();
        w.remove_temporary();
        break;
      case Mode::device: {
        const int fd = w.out.fd;
        w.out.fd = -1;
        if (::close(fd) != 0) fail(w.shown, errno_text(errno));
        break;
      }
    }
  } catch (...) {
    w.target_fd.reset();
    w.remove_temporary();
    throw;
  }
  w.committed = true;
}

void write_file(const std::filesystem::path& path, std::string_view text) {
  FileWriter out(path);
  out.stream().write(text.data(), static_cast<std::streamsize>(text.size()));
  out.commit();
}

void remove_pending_temporaries() noexcept {
  for (Slot& s : g_pending)
    if (s.state.load(std::memory_order_acquire) == 2) ::unlink(s.path.data());
}

}  // namespace orthomech
