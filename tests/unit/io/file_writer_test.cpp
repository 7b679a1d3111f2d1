// FileWriter (io/file_writer.hpp; docs/cli.md "How outputs are written"): what each kind of
// target becomes after a write, checked on the file system itself (lstat, inode numbers, modes,
// owners, the directory's entries) rather than on the writer's own report.
#include "orthomech/io/file_writer.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

namespace fs = std::filesystem;

// The names in a directory, sorted (hidden temporaries included).
std::vector<std::string> entries(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

void put(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

struct stat lstat_of(const fs::path& p) {
  struct stat st {};
  EXPECT_EQ(::lstat(p.c_str(), &st), 0) << p;
  return st;
}

// The message of the std::runtime_error that f throws ("" when it throws none).
template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(FileWriter, SymlinkChain_TargetReplaced_LinksStayLinks) {
  const test::TempDir dir("orthomech_fw_link_");
  put(dir.path / "real.txt", "old\n");
  fs::create_symlink("real.txt", dir.path / "link1");  // relative to the link's directory
  fs::create_symlink(dir.path / "link1", dir.path / "link2");
  write_file(dir.path / "link2", "new\n");
  EXPECT_TRUE(S_ISLNK(lstat_of(dir.path / "link1").st_mode));
  EXPECT_TRUE(S_ISLNK(lstat_of(dir.path / "link2").st_mode));
  EXPECT_EQ(fs::read_symlink(dir.path / "link1"), "real.txt");
  EXPECT_EQ(test::read_text(dir.path / "real.txt"), "new\n");
  EXPECT_EQ(entries(dir.path), (std::vector<std::string>{"link1", "link2", "real.txt"}));
}

TEST(FileWriter, DanglingSymlink_WritesTheFileItNames_OrFailsWithoutItsDirectory) {
  const test::TempDir dir("orthomech_fw_dangling_");
  fs::create_symlink("made.txt", dir.path / "link");
  write_file(dir.path / "link", "made\n");
  EXPECT_TRUE(S_ISLNK(lstat_of(dir.path / "link").st_mode));
  EXPECT_EQ(test::read_text(dir.path / "made.txt"), "made\n");
  fs::create_symlink("no-such-dir/x.txt", dir.path / "broken");
  const std::string e = error_of([&] { write_file(dir.path / "broken", "x"); });
  EXPECT_NE(e.find("cannot write '" + (dir.path / "broken").string() + "'"), std::string::npos)
      << e;
  EXPECT_TRUE(S_ISLNK(lstat_of(dir.path / "broken").st_mode));
}

// Both names keep one inode and see the new text, longer and then shorter than the old one (the
// in-place overwrite truncates to the new size); the staging temporary is gone.
TEST(FileWriter, HardLink_InodeKept_BothNamesSeeTheNewText) {
  const test::TempDir dir("orthomech_fw_hard_");
  put(dir.path / "a.txt", "old text\n");
  fs::create_hard_link(dir.path / "a.txt", dir.path / "b.txt");
  const ino_t inode = lstat_of(dir.path / "a.txt").st_ino;
  const std::string longer(100000, 'x');  // more than FileWriter's 64 KiB buffer
  write_file(dir.path / "a.txt", longer);
  EXPECT_EQ(lstat_of(dir.path / "a.txt").st_ino, inode);
  EXPECT_EQ(lstat_of(dir.path / "b.txt").st_ino, inode);
  EXPECT_EQ(lstat_of(dir.path / "b.txt").st_nlink, 2u);
  EXPECT_EQ(test::read_text(dir.path / "b.txt"), longer);
  write_file(dir.path / "b.txt", "short\n");
  EXPECT_EQ(test::read_text(dir.path / "a.txt"), "short\n");
  EXPECT_EQ(lstat_of(dir.path / "a.txt").st_ino, inode);
  EXPECT_EQ(entries(dir.path), (std::vector<std::string>{"a.txt", "b.txt"}));
}

// A hard-linked file on a full disk is not touched: on a 64 KiB tmpfs (mounted here; root only)
// with 40 KiB free, the 30000 new bytes fit in the staging temporary (8 pages) but the file
// cannot grow from 2 pages to 8 (the reservation fails before the first old byte is
// overwritten): ENOSPC, both names keep the old text and their inode, no temporary is left.
TEST(FileWriter, HardLink_FullDisk_FailsBeforeOverwriting_AsRoot) {
  const test::TempDir dir("orthomech_fw_full_");
  if (::geteuid() != 0 || ::mount("tmpfs", dir.path.c_str(), "tmpfs", 0, "size=64k") != 0)
    GTEST_SKIP() << "needs root and the right to mount a tmpfs";
  struct Unmount {
    const fs::path& p;
    ~Unmount() { ::umount2(p.c_str(), MNT_DETACH); }
  } unmount{dir.path};
  const std::string old(8192, 'o');
  put(dir.path / "a", old);
  fs::create_hard_link(dir.path / "a", dir.path / "b");
  put(dir.path / "fill", std::string(16384, 'f'));  // 64 - 8 - 16 = 40 KiB free
  const std::string e = error_of([&] { write_file(dir.path / "a", std::string(30000, 'n')); });
  EXPECT_EQ(e, "cannot write '" + (dir.path / "a").string() + "': No space left on device");
  EXPECT_EQ(test::read_text(dir.path / "a"), old);
  EXPECT_EQ(test::read_text(dir.path / "b"), old);
  EXPECT_EQ(lstat_of(dir.path / "b").st_nlink, 2u);
  EXPECT_EQ(entries(dir.path), (std::vector<std::string>{"a", "b", "fill"}));
  fs::remove(dir.path / "fill");  // room now: the same write succeeds, in place
  write_file(dir.path / "a", std::string(30000, 'n'));
  EXPECT_EQ(test::read_text(dir.path / "b"), std::string(30000, 'n'));
}

TEST(FileWriter, ExistingFile_ModeKept) {
  const test::TempDir dir("orthomech_fw_mode_");
  const fs::path file = dir.path / "out.txt";
  put(file, "old\n");
  ASSERT_EQ(::chmod(file.c_str(), 0640), 0);
  write_file(file, "new\n");
  EXPECT_EQ(lstat_of(file).st_mode & 07777, 0640u);
  EXPECT_EQ(test::read_text(file), "new\n");
}

// A new file is created as any program creates it: 0666 less the umask (027 here: 0640), not
// mkstemp's 0600.
TEST(FileWriter, NewFile_Mode0666LessUmask) {
  const test::TempDir dir("orthomech_fw_umask_");
  const mode_t old = ::umask(027);
  write_file(dir.path / "new.txt", "new\n");
  ::umask(old);
  EXPECT_EQ(lstat_of(dir.path / "new.txt").st_mode & 07777, 0640u);
}

// As root: a file of another owner (nobody, 65534) keeps its owner and group.
TEST(FileWriter, ExistingFile_OwnerKept_AsRoot) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to give a file to another owner";
  const test::TempDir dir("orthomech_fw_owner_");
  const fs::path file = dir.path / "out.txt";
  put(file, "old\n");
  ASSERT_EQ(::chown(file.c_str(), 65534, 65534), 0);
  write_file(file, "new\n");
  EXPECT_EQ(lstat_of(file).st_uid, 65534u);
  EXPECT_EQ(lstat_of(file).st_gid, 65534u);
  EXPECT_EQ(test::read_text(file), "new\n");
}

// A FIFO with a reader receives the bytes and is still a FIFO. The reader opens it non-blocking
// first (so that the writer finds a reader), then reads until it has every byte.
TEST(FileWriter, Fifo_WithReader_ReceivesTheBytes_StaysAFifo) {
  const test::TempDir dir("orthomech_fw_fifo_");
  const fs::path fifo = dir.path / "pipe";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const int rd = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
  ASSERT_GE(rd, 0);
  const std::string text = "through the pipe\n";
  std::string received;
  std::thread reader([&] {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    char buf[256];
    while (received.size() < text.size() && std::chrono::steady_clock::now() < deadline) {
      const ssize_t n = ::read(rd, buf, sizeof buf);
      if (n > 0)
        received.append(buf, static_cast<size_t>(n));
      else
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  });
  write_file(fifo, text);
  reader.join();
  ::close(rd);
  EXPECT_EQ(received, text);
  EXPECT_TRUE(S_ISFIFO(lstat_of(fifo).st_mode));
}

TEST(FileWriter, Fifo_WithoutReader_IsAnError_NoHang_StaysAFifo) {
  const test::TempDir dir("orthomech_fw_fifo_none_");
  const fs::path fifo = dir.path / "pipe";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string e = error_of([&] { write_file(fifo, "x"); });
  EXPECT_EQ(e, "cannot write '" + fifo.string() + "': no process is reading the FIFO");
  EXPECT_TRUE(S_ISFIFO(lstat_of(fifo).st_mode));
  EXPECT_EQ(entries(dir.path), std::vector<std::string>{"pipe"});
}

TEST(FileWriter, DevNull_Works_StaysACharacterDevice) {
  EXPECT_EQ(error_of([] { write_file("/dev/null", std::string(200000, 'x')); }), "");
  EXPECT_TRUE(S_ISCHR(lstat_of("/dev/null").st_mode));
}

TEST(FileWriter, DevFull_NoSpaceLeft_StaysACharacterDevice) {
  const std::string e = error_of([] { write_file("/dev/full", "report\n"); });
  EXPECT_EQ(e, "cannot write '/dev/full': No space left on device");
  EXPECT_TRUE(S_ISCHR(lstat_of("/dev/full").st_mode));
}

TEST(FileWriter, Directory_Refused) {
  const test::TempDir dir("orthomech_fw_dir_");
  fs::create_directory(dir.path / "sub");
  EXPECT_EQ(error_of([&] { write_file(dir.path / "sub", "x"); }),
            "cannot write '" + (dir.path / "sub").string() + "': it is a directory");
  EXPECT_TRUE(fs::is_directory(dir.path / "sub"));
  EXPECT_EQ(entries(dir.path), std::vector<std::string>{"sub"});
}

// The content fails while it is produced (an exception before commit, as write_cycle_csv's): the
// temporary that existed meanwhile is gone and the target is as it was. The same for a new
// file (nothing created) and for a hard-linked one (its staging temporary).
TEST(FileWriter, FailureBeforeCommit_NoTemporaryLeft_TargetUntouched) {
  const test::TempDir dir("orthomech_fw_fail_");
  const auto fail_midway = [&](const std::string& name, size_t entries_meanwhile) {
    try {
      FileWriter w(dir.path / name);
      w.stream() << std::string(100000, 'y');  // past the 64 KiB buffer: on disk
      EXPECT_EQ(entries(dir.path).size(), entries_meanwhile) << name << ": no temporary seen";
      throw std::invalid_argument("the content failed");
    } catch (const std::invalid_argument&) {
    }
  };
  put(dir.path / "out.txt", "old\n");
  fail_midway("out.txt", 2);
  EXPECT_EQ(entries(dir.path), std::vector<std::string>{"out.txt"});
  EXPECT_EQ(test::read_text(dir.path / "out.txt"), "old\n");
  fail_midway("new.txt", 2);  // nothing created
  EXPECT_EQ(entries(dir.path), std::vector<std::string>{"out.txt"});
  fs::create_hard_link(dir.path / "out.txt", dir.path / "twin.txt");
  fail_midway("twin.txt", 3);  // the staging temporary
  EXPECT_EQ(entries(dir.path), (std::vector<std::string>{"out.txt", "twin.txt"}));
  EXPECT_EQ(test::read_text(dir.path / "twin.txt"), "old\n");
}

// A child writing the file is killed by SIGTERM while its temporary exists (the parent sees it
// in the directory first): a handler like cli/main.cpp's removes it and re-raises, so the child
// dies of SIGTERM, no temporary is left and the target keeps its old text. For a single-name
// target and for a hard-linked one (its staging temporary).
void expect_sigterm_leaves_no_temporary(bool hard_link) {
  const test::TempDir dir("orthomech_fw_sigterm_");
  const fs::path file = dir.path / "out.csv";
  put(file, "old\n");
  std::vector<std::string> before = {"out.csv"};
  if (hard_link) {
    fs::create_hard_link(file, dir.path / "twin.csv");
    before.push_back("twin.csv");
  }
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    struct sigaction sa {};
    sa.sa_handler = [](int sig) {
      remove_pending_temporaries();
      (void)std::raise(sig);
    };
    sa.sa_flags = SA_RESETHAND;
    ::sigaction(SIGTERM, &sa, nullptr);
    FileWriter w(file);
    w.stream() << std::string(1 << 20, 'z');  // 1 MiB of rows, on disk in the temporary
    w.stream().flush();
    (void)!::write(ready[1], "r", 1);
    for (;;) ::pause();  // a slow writer: the rest never comes
  }
  ::close(ready[1]);
  char c = 0;
  ASSERT_EQ(::read(ready[0], &c, 1), 1);
  ::close(ready[0]);
  EXPECT_EQ(entries(dir.path).size(), before.size() + 1) << "the temporary exists mid-write";
  ASSERT_EQ(::kill(child, SIGTERM), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM) << status;
  EXPECT_EQ(entries(dir.path), before);
  EXPECT_EQ(test::read_text(file), "old\n");
}

TEST(FileWriter, SigtermMidWrite_NoTemporaryLeft_OldContentKept) {
  expect_sigterm_leaves_no_temporary(false);
}

TEST(FileWriter, SigtermMidWrite_HardLinked_NoTemporaryLeft_OldContentKept) {
  expect_sigterm_leaves_no_temporary(true);
}

}  // namespace
}  // namespace orthomech
