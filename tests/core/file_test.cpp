// The hosted layer's atomic output (AtomicFile): what is in place after a commit, and that
// nothing is left behind otherwise, with and without the fsync started in the background.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "splintcore/platform.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

// Bytes that differ from one offset to the next (a torn or misplaced write shows).
std::vector<uint8_t> pattern(size_t n) {
  std::vector<uint8_t> b(n);
  for (size_t i = 0; i < n; ++i) b[i] = static_cast<uint8_t>(i * 131 + i / 977);
  return b;
}

std::vector<uint8_t> contents(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

size_t entries(const fs::path& dir) {
  size_t n = 0;
  for (const auto& e : fs::directory_iterator(dir)) n += e.exists() ? 1 : 0;
  return n;
}

// Writes `bytes` in 64,000-byte pieces (the STL writer's), then goes back and patches 4 bytes
// at offset 80 (as a binary STL of unknown count does): more than the writeback's MiB step,
// so the writeback is started several times and once before the seek.
void write_pieces(AtomicFile* f, std::vector<uint8_t>* bytes) {
  const ByteSink sink = f->sink();
  for (size_t at = 0; at < bytes->size(); at += 64000) {
    const size_t n = bytes->size() - at < 64000 ? bytes->size() - at : 64000;
    ASSERT_TRUE(sink.write(sink.user, bytes->data() + at, n));
  }
  const uint8_t patch[4] = {1, 2, 3, 4};
  ASSERT_TRUE(sink.seek(sink.user, 80));
  ASSERT_TRUE(sink.write(sink.user, patch, 4));
  ASSERT_TRUE(sink.seek(sink.user, bytes->size()));
  std::copy(patch, patch + 4, bytes->begin() + 80);
}

TEST(AtomicFile, CommitPutsTheBytesInPlaceWithOrWithoutTheBackgroundSync) {
  TempDir dir("file", "commit");
  for (int background = 0; background < 2; ++background) {
    const fs::path out = dir.path / ("out" + std::to_string(background) + ".bin");
    std::vector<uint8_t> bytes = pattern((size_t{5} << 20) + 12345);
    AtomicFile f;
    SPLINTCORE_ASSERT_OK(f.open(out.string().c_str()));
    write_pieces(&f, &bytes);
    EXPECT_FALSE(fs::exists(out));  // only the temporary file so far
    if (background == 1) {
      SPLINTCORE_ASSERT_OK(f.sync_in_background());
      EXPECT_FALSE(fs::exists(out));
      EXPECT_FALSE(f.sync_in_background().is_ok());  // once
    }
    SPLINTCORE_ASSERT_OK(f.commit());
    EXPECT_TRUE(contents(out) == bytes) << "background " << background;
    EXPECT_EQ(entries(dir.path), static_cast<size_t>(background + 1));  // no temporary left
  }
}

TEST(AtomicFile, AbortOrDestructionAfterTheBackgroundSyncLeavesNothing) {
  TempDir dir("file", "abort");
  const fs::path out = dir.path / "out.bin";
  std::vector<uint8_t> bytes = pattern(size_t{3} << 20);
  {
    AtomicFile f;
    SPLINTCORE_ASSERT_OK(f.open(out.string().c_str()));
    write_pieces(&f, &bytes);
    SPLINTCORE_ASSERT_OK(f.sync_in_background());
    EXPECT_EQ(entries(dir.path), 1u);  // the temporary file
    f.abort();
    EXPECT_EQ(entries(dir.path), 0u);
    EXPECT_FALSE(f.commit().is_ok());  // nothing left to commit
  }
  {
    AtomicFile f;
    SPLINTCORE_ASSERT_OK(f.open(out.string().c_str()));
    write_pieces(&f, &bytes);
    SPLINTCORE_ASSERT_OK(f.sync_in_background());
  }  // destroyed while (or after) syncing
  EXPECT_EQ(entries(dir.path), 0u);
  // An earlier file of that name stays as it was when a later one is not committed.
  const std::vector<uint8_t> first = pattern(1000);
  {
    AtomicFile f;
    SPLINTCORE_ASSERT_OK(f.open(out.string().c_str()));
    const ByteSink sink = f.sink();
    ASSERT_TRUE(sink.write(sink.user, first.data(), first.size()));
    SPLINTCORE_ASSERT_OK(f.commit());
  }
  {
    AtomicFile f;
    SPLINTCORE_ASSERT_OK(f.open(out.string().c_str()));
    write_pieces(&f, &bytes);
    SPLINTCORE_ASSERT_OK(f.sync_in_background());
  }
  EXPECT_TRUE(contents(out) == first);
  EXPECT_EQ(entries(dir.path), 1u);
}

// What AtomicFile refuses, and a commit whose rename fails (the output's name is a folder):
// a clear error naming the file, the temporary file removed, the folder as it was.
TEST(AtomicFile, RefusalsAndAFailedRenameLeaveNothingBehind) {
  TempDir dir("file", "refusals");
  AtomicFile f;
  Status s = f.open("");
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_STREQ(s.message(), "output path is empty or too long");
  const std::string long_path = (dir.path / std::string(4100, 'x')).string();
  EXPECT_STREQ(f.open(long_path.c_str()).message(), "output path is empty or too long");
  EXPECT_STREQ(f.commit().message(), "no open output file");
  EXPECT_STREQ(f.sync_in_background().message(), "no open output file to sync");
  EXPECT_EQ(entries(dir.path), 0u);
  // A folder that does not exist: the temporary file cannot be made (the cause given), and
  // the writer is left closed, with no temporary name that commit() or abort() would rename
  // or remove (after EEXIST, the same path, that name is another file's).
  const fs::path nowhere = dir.path / "no such folder" / "splint.stl";
  s = f.open(nowhere.string().c_str());
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_EQ(std::string(s.message()).rfind("cannot create temporary output file: ", 0), 0u)
      << s.message();
  EXPECT_NE(std::string(s.message()).find("No such file or directory"), std::string::npos)
      << s.message();
  EXPECT_STREQ(f.commit().message(), "no open output file");
  EXPECT_EQ(entries(dir.path), 0u);

  const fs::path folder = dir.path / "splint.stl";
  fs::create_directories(folder / "inside");
  SPLINTCORE_ASSERT_OK(f.open(folder.string().c_str()));
  const std::vector<uint8_t> bytes = pattern(1000);
  const ByteSink sink = f.sink();
  ASSERT_TRUE(sink.write(sink.user, bytes.data(), bytes.size()));
  EXPECT_EQ(entries(dir.path), 2u);  // the folder and the temporary file
  s = f.commit();
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_EQ(std::string(s.message()).rfind("cannot move the output into place: ", 0), 0u)
      << s.message();
  EXPECT_EQ(std::string(s.file()), folder.string());
  EXPECT_EQ(entries(dir.path), 1u);  // the temporary file is gone
  EXPECT_TRUE(fs::is_directory(folder / "inside"));
}

// The temporary name taken (O_EXCL): a file that already has it is another's, and stays as it
// was through the failed open, commit() and abort(). Its name is predicted from a first open's
// (the counter is this process's, one more each open).
TEST(AtomicFile, ATemporaryNameTakenByAnotherFileLeavesThatFileAlone) {
  TempDir dir("file", "taken");
  AtomicFile f;
  const fs::path first = dir.path / "first.stl";
  SPLINTCORE_ASSERT_OK(f.open(first.string().c_str()));
  std::string temp;
  for (const auto& e : fs::directory_iterator(dir.path)) temp = e.path().filename().string();
  f.abort();
  const std::string prefix = "first.stl.tmp-" + std::to_string(::getpid()) + "-";
  ASSERT_EQ(temp.rfind(prefix, 0), 0u) << temp;
  const unsigned next = static_cast<unsigned>(std::stoul(temp.substr(prefix.size()))) + 1;
  const fs::path other =
      dir.path / ("second.stl.tmp-" + std::to_string(::getpid()) + "-" + std::to_string(next));
  const std::vector<uint8_t> theirs = pattern(100);
  {
    std::ofstream out(other, std::ios::binary);
    out.write(reinterpret_cast<const char*>(theirs.data()),
              static_cast<std::streamsize>(theirs.size()));
  }
  const Status s = f.open((dir.path / "second.stl").string().c_str());
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_NE(std::string(s.message()).find("File exists"), std::string::npos) << s.message();
  EXPECT_STREQ(f.commit().message(), "no open output file");
  f.abort();
  EXPECT_EQ(contents(other), theirs);
  EXPECT_FALSE(fs::exists(dir.path / "second.stl"));
  EXPECT_EQ(entries(dir.path), 1u);
}

// A write past the file size limit (as a full disk: the write fails, here with EFBIG) fails
// cleanly: the writer's error gets the system's cause, and nothing is left behind.
TEST(AtomicFile, AWritePastTheFileSizeLimitFailsWithItsCause) {
  TempDir dir("file", "fsize");
  const fs::path path = dir.path / "splint.stl";
  AtomicFile f;
  SPLINTCORE_ASSERT_OK(f.open(path.string().c_str()));
  const Status unrelated = Status::error(StatusCode::kInvalidMesh, "not about the file");
  EXPECT_STREQ(f.with_write_cause(unrelated).message(), "not about the file");
  const std::vector<uint8_t> bytes = pattern(size_t{1} << 20);
  const ByteSink sink = f.sink();
  bool written = true;
  Status s;
  {
    test::FileSizeLimit limit(64 << 10);
    for (size_t at = 0; at < bytes.size() && written; at += 64000) {
      written =
          sink.write(sink.user, bytes.data() + at, std::min<size_t>(64000, bytes.size() - at));
    }
    s = written ? f.commit()
                : f.with_write_cause(Status::error(StatusCode::kIoError, "write failed"));
  }
  EXPECT_FALSE(written);
  EXPECT_STREQ(s.message(), "write failed: File too large");
  EXPECT_EQ(f.with_write_cause(unrelated).code(), StatusCode::kInvalidMesh);
  f.abort();
  EXPECT_EQ(entries(dir.path), 0u);
}

// The child of the test below: two outputs open (one written to), SIGHUP ignored beforehand
// and raised (nothing happens), then `sig`. Its exit status says which step went wrong.
[[noreturn]] void open_two_then_raise(const fs::path& dir, int sig) {
  std::signal(SIGHUP, SIG_IGN);
  remove_temporary_outputs_on_signals();
  AtomicFile first;
  AtomicFile second;
  if (!first.open((dir / "a.stl").string().c_str()).is_ok() ||
      !second.open((dir / "b.stl").string().c_str()).is_ok()) {
    std::_Exit(3);
  }
  const std::vector<uint8_t> bytes = pattern(1000);
  const ByteSink sink = first.sink();
  if (!sink.write(sink.user, bytes.data(), bytes.size())) std::_Exit(4);
  if (entries(dir) != 2) std::_Exit(5);
  std::raise(SIGHUP);
  if (entries(dir) != 2) std::_Exit(6);
  std::raise(sig);
  std::_Exit(7);
}

// A destination that is a pipe or a device is written in place: it stays a pipe (renaming over
// it would have replaced it with a regular file; as root, /dev/null too), the reader gets the
// bytes, and a seek (which a pipe cannot do) fails with the system's cause.
TEST(AtomicFile, APipeOrADeviceIsWrittenInPlace) {
  TempDir dir("file", "fifo");
  const fs::path fifo = dir.path / "splint.stl";
  ASSERT_EQ(::mkfifo(fifo.string().c_str(), 0600), 0);
  const std::vector<uint8_t> bytes = pattern(300000);  // more than a pipe holds
  // The read end opened first (without waiting for a writer), so that open() does not wait
  // for it; read from once open() is done: should open() not write to the pipe, the reader
  // sees no writer and ends at once (the test fails, it does not hang).
  const int read_end = ::open(fifo.string().c_str(), O_RDONLY | O_NONBLOCK);
  ASSERT_GE(read_end, 0);
  AtomicFile f;
  SPLINTCORE_ASSERT_OK(f.open(fifo.string().c_str()));
  std::vector<uint8_t> got;
  std::thread reader([&] {
    ::fcntl(read_end, F_SETFL, ::fcntl(read_end, F_GETFL) & ~O_NONBLOCK);
    uint8_t buffer[4096];
    for (ssize_t n; (n = ::read(read_end, buffer, sizeof buffer)) > 0;) {
      got.insert(got.end(), buffer, buffer + n);
    }
    ::close(read_end);
  });
  const ByteSink sink = f.sink();
  EXPECT_TRUE(sink.write(sink.user, bytes.data(), bytes.size()));
  EXPECT_FALSE(sink.seek(sink.user, 80));
  EXPECT_STREQ(f.with_write_cause(Status::error(StatusCode::kIoError, "could not patch")).message(),
               "could not patch: Illegal seek");
  SPLINTCORE_EXPECT_OK(f.commit());
  reader.join();
  EXPECT_EQ(got, bytes);
  struct stat st;
  ASSERT_EQ(::stat(fifo.string().c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  EXPECT_EQ(entries(dir.path), 1u);
  EXPECT_STREQ(f.commit().message(), "no open output file");
  // A device (the null device's numbers, made here; only root may make one).
  const fs::path device = dir.path / "null";
  if (::mknod(device.string().c_str(), S_IFCHR | 0600, makedev(1, 3)) != 0) return;
  SPLINTCORE_ASSERT_OK(f.open(device.string().c_str()));
  EXPECT_TRUE(sink.write(sink.user, bytes.data(), bytes.size()));
  SPLINTCORE_EXPECT_OK(f.commit());
  ASSERT_EQ(::stat(device.string().c_str(), &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
  EXPECT_EQ(entries(dir.path), 2u);
}

// A symbolic link to a regular file: the file it names gets the bytes, atomically, and the link
// stays a link (as /dev/stdout redirected to a file must). A link to nothing is replaced.
TEST(AtomicFile, ALinkToAFileHasTheFileReplacedAndStays) {
  TempDir dir("file", "link");
  fs::create_directories(dir.path / "real");
  const fs::path target = dir.path / "real" / "splint.stl", link = dir.path / "latest.stl";
  std::ofstream(target) << "old";
  fs::create_symlink(target, link);
  const std::vector<uint8_t> bytes = pattern(1000);
  AtomicFile f;
  SPLINTCORE_ASSERT_OK(f.open(link.string().c_str()));
  ByteSink sink = f.sink();
  ASSERT_TRUE(sink.write(sink.user, bytes.data(), bytes.size()));
  EXPECT_EQ(entries(dir.path / "real"), 2u);  // the temporary file beside the target
  SPLINTCORE_ASSERT_OK(f.commit());
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(contents(target), bytes);
  EXPECT_EQ(entries(dir.path / "real"), 1u);
  EXPECT_EQ(entries(dir.path), 2u);

  const fs::path dangling = dir.path / "dangling.stl";
  fs::create_symlink(dir.path / "nowhere" / "x.stl", dangling);
  SPLINTCORE_ASSERT_OK(f.open(dangling.string().c_str()));
  sink = f.sink();
  ASSERT_TRUE(sink.write(sink.user, bytes.data(), bytes.size()));
  SPLINTCORE_ASSERT_OK(f.commit());
  EXPECT_FALSE(fs::is_symlink(dangling));
  EXPECT_EQ(contents(dangling), bytes);
}

// A file replaced keeps its permissions; a new one has the default ones.
TEST(AtomicFile, AReplacedFileKeepsItsPermissions) {
  TempDir dir("file", "mode");
  const fs::path path = dir.path / "report.json";
  std::ofstream(path) << "old";
  fs::permissions(path, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  AtomicFile f;
  SPLINTCORE_ASSERT_OK(f.open(path.string().c_str()));
  const uint8_t byte = 'x';
  const ByteSink sink = f.sink();
  ASSERT_TRUE(sink.write(sink.user, &byte, 1));
  SPLINTCORE_ASSERT_OK(f.commit());
  EXPECT_EQ(fs::status(path).permissions(),
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  EXPECT_EQ(contents(path), std::vector<uint8_t>{'x'});
}

// Stopped by a signal while outputs are open: with remove_temporary_outputs_on_signals() the
// temporary files go and the process still ends by that signal; a signal ignored before it
// was called stays ignored.
TEST(AtomicFileDeathTest, ASignalRemovesTheTemporaryFilesAndStillEndsTheProcess) {
  TempDir dir("file", "signal");
  for (const int sig : {SIGTERM, SIGINT, SIGPIPE}) {
    EXPECT_EXIT(open_two_then_raise(dir.path, sig), testing::KilledBySignal(sig), "");
    EXPECT_EQ(entries(dir.path), 0u) << sig;
  }
}

// FileSource and read_file: a folder is refused by name, a device is not a regular file, a
// file over the caller's limit is refused before anything is allocated, and a path longer
// than a status can hold keeps its end (the file's own name) in the source's name.
TEST(FileSource, AFolderADeviceALimitAndALongPath) {
  TempDir dir("file", "source");
  FileSource src;
  Status s = src.open(dir.path.string().c_str());
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_EQ(std::string(s.message()), std::string("cannot read: ") + std::strerror(EISDIR));

  test::TestArena t(1 << 16);
  Span<uint8_t> out;
  struct stat st;
  if (::stat("/dev/null", &st) == 0 && S_ISCHR(st.st_mode)) {
    s = read_file(t.arena, "/dev/null", 1000, &out);
    EXPECT_EQ(s.code(), StatusCode::kUnsupported);
    EXPECT_STREQ(s.message(), "not a regular file");
    EXPECT_STREQ(s.file(), "/dev/null");
  }

  const fs::path file = dir.path / "case.json";
  const std::vector<uint8_t> bytes = pattern(100);
  std::ofstream(file, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(100));
  const size_t used = t.arena.used();
  s = read_file(t.arena, file.string().c_str(), 99, &out);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded);
  EXPECT_STREQ(s.message(), "file is 100 bytes, over the limit of 99");
  EXPECT_EQ(t.arena.used(), used);
  EXPECT_TRUE(out.empty());
  SPLINTCORE_ASSERT_OK(read_file(t.arena, file.string().c_str(), 100, &out));
  EXPECT_TRUE(std::vector<uint8_t>(out.data(), out.data() + out.size()) == bytes);

  std::string deep = dir.path.string();
  for (int i = 0; i < 100; ++i) deep += "/.";
  deep += "/case.json";
  ASSERT_GT(deep.size(), Status::kFileCapacity);
  SPLINTCORE_ASSERT_OK(src.open(deep.c_str()));
  const std::string name = src.source().name;
  EXPECT_EQ(name.size(), Status::kFileCapacity - 1);
  EXPECT_EQ(name, deep.substr(deep.size() - name.size()));
  EXPECT_EQ(src.source().size, 100u);
}

// A regular file that stat calls empty: truly empty, its size is 0 and reading gives nothing;
// one that makes its bytes as it is read (procfs) is a stream of unknown size, read whole
// (its first byte, read ahead to tell them apart, is not lost).
TEST(FileSource, ARegularFileOfSizeZeroThatHasBytesIsAStream) {
  TempDir dir("file", "zero");
  const fs::path empty = dir.path / "empty.stl";
  std::ofstream(empty, std::ios::binary).close();
  FileSource src;
  SPLINTCORE_ASSERT_OK(src.open(empty.string().c_str()));
  ByteSource in = src.source();
  EXPECT_EQ(in.size, 0u);
  uint8_t buffer[4096];
  EXPECT_EQ(in.read(in.user, buffer, sizeof(buffer)), 0);

  const char* const kProc = "/proc/self/status";
  struct stat st;
  if (::stat(kProc, &st) != 0 || !S_ISREG(st.st_mode) || st.st_size != 0) {
    GTEST_SKIP() << kProc << " is not a regular file of size 0 here";
  }
  SPLINTCORE_ASSERT_OK(src.open(kProc));
  in = src.source();
  EXPECT_EQ(in.size, kUnknownSize);
  std::string text;
  int64_t n = 0;
  while ((n = in.read(in.user, buffer, sizeof(buffer))) > 0) {
    text.append(reinterpret_cast<const char*>(buffer), static_cast<size_t>(n));
  }
  EXPECT_EQ(n, 0);
  EXPECT_EQ(text.compare(0, 5, "Name:"), 0) << text.substr(0, 40);
}

}  // namespace
}  // namespace splintcore
