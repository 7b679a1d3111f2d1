#pragma once
// Every file the tool writes (assemble --write/--in-place, cycle --out/--report/--animate,
// render --out, sweep's variants.csv and summary.json, the drivers' CSV, the gnuplot script)
// goes through FileWriter, which treats the target by what it is (docs/cli.md "How outputs are
// written"):
//
// 1. A symbolic link (or a chain of them) is followed to its final target, which is what gets
//    written; the link stays a link. A dangling link writes the file it names, if its directory
//    exists.
// 2. A regular file with one name, or a new file: the bytes go to a hidden temporary file in the
//    target's directory (".NAME.tmp-XXXXXX"), which is flushed, fsync'd, given the target's mode,
//    owner and group (a new file: 0666 less the umask, as any program creates it) and renamed
//    over the target: a reader sees the old file or the new one, never a half-written one.
// 3. A regular file with several names (hard links): the inode is kept, so that every name sees
//    the new text. The bytes are staged in a temporary file first; at commit the space for the
//    new size is reserved (posix_fallocate; where the filesystem cannot, the part beyond the old
//    size is written first), then the file is overwritten from offset 0, truncated to the size
//    and fsync'd, with SIGINT, SIGTERM and SIGHUP blocked in the calling thread. A full disk
//    therefore fails before the first old byte is overwritten; a SIGKILL (or a power cut) during
//    the overwrite can leave the file partly overwritten.
// 4. A character device or a FIFO is written into, never replaced (/dev/null, /dev/stdout, a
//    named pipe): a FIFO that no process reads is an error, not a hang; /dev/full fails with "No
//    space left on device". A directory, a socket or a block device is refused.
//
// Temporary files are removed on every failure and, through remove_pending_temporaries(), by the
// CLI's handler of SIGINT, SIGTERM and SIGHUP (cli/main.cpp). Failures throw std::runtime_error
// "cannot write 'PATH': reason", PATH as the caller gave it.
#include <filesystem>
#include <memory>
#include <ostream>
#include <string_view>

namespace orthomech {

// A file written piece by piece (the cycle's CSV streams its rows): stream() takes the bytes,
// commit() puts them in place. Destroyed without commit() (an exception while the content was
// produced), the target is left as it was (a device or FIFO has received what was written so
// far) and the temporary files are removed.
class FileWriter {
 public:
  // Resolves the target and opens what the bytes go to (a temporary file, the device, the
  // FIFO). Throws std::runtime_error naming `path` when it cannot be written.
  explicit FileWriter(const std::filesystem::path& path);
  ~FileWriter();
  FileWriter(const FileWriter&) = delete;
  FileWriter& operator=(const FileWriter&) = delete;

  // The stream the content is written to (buffered; a write error is reported by commit()).
  [[nodiscard]] std::ostream& stream();
  // Flushes and puts the content in place (rename, in-place overwrite, or the last write to a
  // device). Throws std::runtime_error naming the path on failure.
  void commit();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Writes `text` to `path` as FileWriter does. Throws std::runtime_error naming the path.
void write_file(const std::filesystem::path& path, std::string_view text);

// Unlinks every temporary file that a FileWriter of this process has open now (a fixed table of
// at most kMaxPendingTemporaries paths; a writer beyond that many at once keeps its temporary
// out of the table). Async-signal-safe: it reads the table with lock-free atomics and calls
// unlink() only; meant for a signal handler that then re-raises the signal.
void remove_pending_temporaries() noexcept;
inline constexpr int kMaxPendingTemporaries = 64;

}  // namespace orthomech
