// What the tools put out (tools/common/cli.h). OutputSet: a run's files placed together or not
// at all. Nothing is in place before commit(); a failure at any file (a write past the file
// size limit, as on a full disk; the set destroyed) leaves none of them in place and the files
// of an earlier run as they were; a destination that is a folder is refused before any
// rename. write_bytes_atomically: bytes written that way. printable(): what a message quotes
// from an input reaches the terminal inert.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "common/cli.h"
#include "splintcore/platform.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

std::string contents(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void put(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

size_t entries(const fs::path& dir) {
  size_t n = 0;
  for (const auto& e : fs::directory_iterator(dir)) n += e.exists() ? 1 : 0;
  return n;
}

// `text` written into a fresh AtomicFile on `path` and kept in `set`; the write's status
// (with its cause) when the sink refuses the bytes.
Status keep_text(cli::OutputSet* set, const fs::path& path, const std::string& text) {
  auto file = std::make_unique<AtomicFile>();
  SPLINTCORE_RETURN_IF_ERROR(file->open(path.string().c_str()));
  const ByteSink sink = file->sink();
  if (!sink.write(sink.user, reinterpret_cast<const uint8_t*>(text.data()), text.size())) {
    return file->with_write_cause(Status::error(StatusCode::kIoError, "write failed"));
  }
  return set->keep(std::move(file));
}

TEST(OutputSet, FilesArePlacedTogetherAtTheCommit) {
  TempDir dir("outputs", "commit");
  const fs::path splint = dir.path / "splint.stl", report = dir.path / "report.json";
  put(report, "old report");
  cli::OutputSet set;
  SPLINTCORE_ASSERT_OK(keep_text(&set, splint, "new splint"));
  SPLINTCORE_ASSERT_OK(keep_text(&set, report, "new report"));
  EXPECT_FALSE(fs::exists(splint));  // kept, not placed
  EXPECT_EQ(contents(report), "old report");
  EXPECT_EQ(entries(dir.path), 3u);  // the old report and two temporary files
  SPLINTCORE_ASSERT_OK(set.commit());
  EXPECT_EQ(contents(splint), "new splint");
  EXPECT_EQ(contents(report), "new report");
  EXPECT_EQ(entries(dir.path), 2u);
  SPLINTCORE_EXPECT_OK(set.commit());  // nothing more to place
}

TEST(OutputSet, ARunThatFailsAtAnyFilePlacesNone) {
  TempDir dir("outputs", "fail");
  const fs::path splint = dir.path / "splint.stl", report = dir.path / "report.json";
  put(splint, "old splint");
  put(report, "old report");
  {
    cli::OutputSet set;  // destroyed without a commit (the run stopped at an error)
    SPLINTCORE_ASSERT_OK(keep_text(&set, splint, "new splint"));
  }
  EXPECT_EQ(contents(splint), "old splint");
  EXPECT_EQ(entries(dir.path), 2u);

  // The second file's write fails past the file size limit (as on a full disk) after the
  // first was written whole and kept: neither is placed, the old ones stay.
  cli::OutputSet set;
  SPLINTCORE_ASSERT_OK(keep_text(&set, splint, "new splint"));
  Status s;
  {
    test::FileSizeLimit limit(64 << 10);
    s = keep_text(&set, report, std::string(size_t{1} << 20, 'r'));
  }
  EXPECT_STREQ(s.message(), "write failed: File too large");
  EXPECT_EQ(contents(report), "old report");
  EXPECT_EQ(contents(splint), "old splint");
}

TEST(OutputSet, AFolderInTheWayIsRefusedBeforeAnyRename) {
  TempDir dir("outputs", "folder");
  const fs::path splint = dir.path / "splint.stl", report = dir.path / "report.json";
  put(splint, "old splint");
  fs::create_directories(report / "inside");
  {
    cli::OutputSet set;
    SPLINTCORE_ASSERT_OK(keep_text(&set, splint, "new splint"));
    SPLINTCORE_ASSERT_OK(keep_text(&set, report, "new report"));
    const Status s = set.commit();
    EXPECT_EQ(s.code(), StatusCode::kIoError);
    EXPECT_STREQ(s.message(), "cannot move the output into place: a folder has its name");
    EXPECT_EQ(std::string(s.file()), report.string());
  }
  EXPECT_EQ(contents(splint), "old splint");
  EXPECT_TRUE(fs::is_directory(report / "inside"));
  EXPECT_EQ(entries(dir.path), 2u);  // no temporary file left
}

// While another holder (another run; here another thread's open of the folder) has the folder
// locked, commit() places nothing; it places the set when the lock is released.
TEST(OutputSet, ACommitInParallelWaitsForTheFolderLock) {
  TempDir dir("outputs", "lock");
  const fs::path splint = dir.path / "splint.stl";
  put(splint, "old splint");
  cli::OutputSet set;
  SPLINTCORE_ASSERT_OK(keep_text(&set, splint, "new splint"));
  const int fd = ::open(dir.path.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX), 0);
  std::atomic<bool> done{false};
  Status s;
  std::thread committer([&] {
    s = set.commit();
    done = true;
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  EXPECT_FALSE(done.load());
  EXPECT_EQ(contents(splint), "old splint");
  ::close(fd);  // releases the lock
  committer.join();
  SPLINTCORE_EXPECT_OK(s);
  EXPECT_EQ(contents(splint), "new splint");
}

// A lock held past the set's wait (a run stopped while it renames): commit() gives up with an
// error naming the folder, places nothing, and the set's temporary files go with it.
TEST(OutputSet, ALockHeldPastTheWaitIsAnErrorAndPlacesNothing) {
  TempDir dir("outputs", "stuck");
  const fs::path splint = dir.path / "splint.stl";
  put(splint, "old splint");
  const int fd = ::open(dir.path.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX), 0);
  Status s;
  {
    cli::OutputSet set;
    set.set_lock_wait(0.2);
    SPLINTCORE_ASSERT_OK(keep_text(&set, splint, "new splint"));
    s = set.commit();
  }
  ::close(fd);
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_NE(std::string(s.message()).find("another process has held this folder's lock for 0 s"),
            std::string::npos)
      << s.message();
  EXPECT_EQ(std::string(s.file()), dir.path.string());
  EXPECT_EQ(contents(splint), "old splint");
  EXPECT_EQ(entries(dir.path), 1u);  // no temporary file left
}

// write_bytes_atomically: the parts in order, placed now or kept in a set; a failed write
// says why and leaves the old file and no temporary file.
TEST(WriteBytesAtomically, PartsInOrderAndAFailedWriteLeavesTheOldFile) {
  TempDir dir("outputs", "bytes");
  const fs::path a = dir.path / "a.txt", b = dir.path / "b.txt";
  const std::string head = "head,", tail = "tail";
  SPLINTCORE_ASSERT_OK(cli::write_bytes_atomically(
      a.string(), {cli::ByteSpan{head.data(), head.size()}, cli::ByteSpan{nullptr, 0},
                   cli::ByteSpan{tail.data(), tail.size()}}));
  EXPECT_EQ(contents(a), "head,tail");
  {
    cli::OutputSet set;
    SPLINTCORE_ASSERT_OK(cli::write_bytes_atomically(b.string(), std::string("kept"), &set));
    EXPECT_FALSE(fs::exists(b));
    SPLINTCORE_ASSERT_OK(set.commit());
  }
  EXPECT_EQ(contents(b), "kept");
  Status s;
  {
    test::FileSizeLimit limit(64 << 10);
    const std::string big(size_t{1} << 20, 'x');
    s = cli::write_bytes_atomically(a.string(), big.data(), big.size());
  }
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_STREQ(s.message(), "cannot write: File too large");
  EXPECT_EQ(std::string(s.file()), a.string());
  EXPECT_EQ(contents(a), "head,tail");
  EXPECT_EQ(entries(dir.path), 2u);
}

TEST(Printable, ControlBytesAreWrittenOutAndTextIsKept) {
  EXPECT_EQ(cli::printable(""), "");
  EXPECT_EQ(cli::printable("plain ascii, UTF-8: \xc3\xbcn\xc3\xaf \xe2\x80\x94 ok"),
            "plain ascii, UTF-8: \xc3\xbcn\xc3\xaf \xe2\x80\x94 ok");
  EXPECT_EQ(cli::printable("\x1b[31mred\x1b[0m"), "\\x1b[31mred\\x1b[0m");
  EXPECT_EQ(cli::printable("a\nsplintcore: fake\tline\x7f"),
            "a\\x0asplintcore: fake\\x09line\\x7f");
  // C1 controls as UTF-8 (U+009B, the one-byte CSI) go; U+00A0 and beyond stay.
  EXPECT_EQ(cli::printable("\xc2\x9b"
                           "2J \xc2\xa0"),
            "\\xc2\\x9b"
            "2J \xc2\xa0");
  EXPECT_EQ(cli::printable("\xc2"), "\xc2");  // a lone lead byte at the end: kept, no overread
}

}  // namespace
}  // namespace splintcore
