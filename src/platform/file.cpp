// Files for hosted builds: a ByteSource over a FILE*, and atomic output (temporary file in the
// destination's folder, fsync, rename), so a failed run never leaves a partial output file.
#include <fcntl.h>
#include <limits.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>

#include "splintcore/platform.h"

namespace splintcore {

namespace {

int64_t file_read(void* user, uint8_t* buffer, size_t capacity) {
  std::FILE* f = static_cast<std::FILE*>(user);
  size_t got = std::fread(buffer, 1, capacity, f);
  if (got == 0 && std::ferror(f)) return -1;
  return static_cast<int64_t>(got);
}

constexpr uint64_t kWritebackStep = uint64_t{1}
                                    << 20;  // AtomicFile: writeback started a MiB at a time

Status errno_error(const char* what, const char* path) {
  Status s = make_error(StatusCode::kIoError, what, ": ", std::strerror(errno));
  s.in_file(path);
  return s;
}

std::atomic<uint32_t> g_temp_counter{0};  // distinct temporary names within one process

// The temporary files of the AtomicFiles open now, for the signal handler: a slot holds a
// temp_path_ from before its file is created until after it is renamed or removed.
constexpr int kTempSlots = 64;
std::atomic<const char*> g_temp_paths[kTempSlots];

int register_temp_path(const char* path) {
  for (int i = 0; i < kTempSlots; ++i) {
    const char* none = nullptr;
    if (g_temp_paths[i].compare_exchange_strong(none, path)) return i;
  }
  return -1;  // more open at once than the slots: this one is not removed on a signal
}

void unregister_temp_path(int* slot) {
  if (*slot >= 0) g_temp_paths[*slot].store(nullptr);
  *slot = -1;
}

// Only what a signal handler may do: atomic loads, unlink, signal and raise.
extern "C" void remove_temporary_outputs(int sig) {
  for (std::atomic<const char*>& slot : g_temp_paths) {
    const char* path = slot.load();
    if (path != nullptr) (void)::unlink(path);
  }
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

// The handler for `sig`, unless the signal is ignored now.
void remove_on(int sig) {
  if (std::signal(sig, remove_temporary_outputs) == SIG_IGN) std::signal(sig, SIG_IGN);
}

}  // namespace

void remove_temporary_outputs_on_signals() {
  static_assert(ATOMIC_POINTER_LOCK_FREE == 2, "the signal handler reads the slots lock-free");
  remove_on(SIGINT);
  remove_on(SIGTERM);
#ifdef SIGHUP
  remove_on(SIGHUP);
#endif
#ifdef SIGPIPE
  remove_on(SIGPIPE);
#endif
#ifdef SIGXFSZ
  std::signal(SIGXFSZ, SIG_IGN);
#endif
}

FileSource::~FileSource() { close(); }

Status FileSource::open(const char* path) {
  close();
  file_ = std::fopen(path, "rb");
  if (file_ == nullptr) return errno_error("cannot open for reading", path);
  owned_ = true;
  return opened(path);
}

Status FileSource::open_standard_input() {
  close();
  file_ = stdin;
  owned_ = false;
  return opened(kStandardInputName);
}

Status FileSource::opened(const char* path) {
  struct stat st;
  if (fstat(fileno(file_), &st) != 0) {  // e.g. a closed standard input
    const int cause = errno;
    close();
    errno = cause;
    return errno_error("cannot read", path);
  }
  if (S_ISDIR(st.st_mode)) {
    close();
    errno = EISDIR;
    return errno_error("cannot read", path);
  }
  if (S_ISREG(st.st_mode)) {
    size_ = static_cast<uint64_t>(st.st_size);
    // A regular file of size 0 may still hold bytes: procfs and sysfs report 0 for what they
    // make as they are read. One byte read ahead (and pushed back) tells them from an empty
    // file; such a file is then read as a stream.
    if (size_ == 0) {
      const int c = std::fgetc(file_);
      if (c != EOF) {
        std::ungetc(c, file_);
        size_ = kUnknownSize;
      }
    }
  } else {
    size_ = kUnknownSize;  // a pipe or device: readers check counts as they go
  }
  size_t n = std::strlen(path);
  if (n >= sizeof(path_)) {
    path += n - (sizeof(path_) - 1);
    n = sizeof(path_) - 1;
  }
  std::memcpy(path_, path, n);
  path_[n] = '\0';
  return Status::ok();
}

ByteSource FileSource::source() {
  ByteSource s;
  s.read = file_read;
  s.user = file_;
  s.size = size_;
  s.name = path_;
  return s;
}

void FileSource::close() {
  if (file_ != nullptr && owned_) std::fclose(file_);
  file_ = nullptr;
  owned_ = false;
  size_ = kUnknownSize;
}

AtomicFile::~AtomicFile() { abort(); }

Status AtomicFile::open(const char* path) {
  abort();
  size_t n = std::strlen(path);
  if (n == 0 || n + 32 >= sizeof(path_)) {
    return make_error(StatusCode::kInvalidArgument, "output path is empty or too long");
  }
  std::memcpy(path_, path, n + 1);
  write_errno_ = 0;
  started_ = 0;
  sync_errno_ = 0;
  // A destination that exists and is neither a regular file nor a folder (/dev/null,
  // /dev/stdout, a FIFO) is written in place: renaming over it would replace the device or the
  // pipe itself with a regular file (as root, /dev/null), and a stream has no whole to swap in.
  struct stat st;
  const bool exists = ::stat(path, &st) == 0;
  if (exists && !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode)) {
    file_ = std::fopen(path, "wb");
    if (file_ == nullptr) return errno_error("cannot open for writing", path);
    direct_ = true;
    return Status::ok();
  }
  // A symbolic link to a regular file: the file it names is replaced, beside itself, and the
  // link stays. (Replacing the link would put the output where the link was, away from the
  // file meant; and /dev/stdout with the standard output redirected to a file is such a link,
  // in /dev.) A link to nothing yet is replaced by the output.
  struct stat link;
  char resolved[PATH_MAX];
  if (exists && ::lstat(path, &link) == 0 && S_ISLNK(link.st_mode) &&
      ::realpath(path, resolved) != nullptr) {
    n = std::strlen(resolved);
    if (n + 32 >= sizeof(path_)) {
      return make_error(StatusCode::kInvalidArgument, "output path is empty or too long");
    }
    std::memcpy(path_, resolved, n + 1);
    path = path_;
  }
  std::snprintf(temp_path_, sizeof(temp_path_), "%s.tmp-%ld-%u", path, static_cast<long>(getpid()),
                g_temp_counter.fetch_add(1));
  slot_ = register_temp_path(temp_path_);  // (the name has this process's id: ours to remove)
  // O_EXCL: never write through a name something else already uses.
  int fd = ::open(temp_path_, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) {
    // Not ours (EEXIST: another file has the name): neither commit() nor abort() may touch it.
    Status s = errno_error("cannot create temporary output file", temp_path_);
    unregister_temp_path(&slot_);
    temp_path_[0] = '\0';
    return s;
  }
  // A file replaced keeps its permissions (a new one has 0644 less the umask). Where they
  // cannot be given (another owner's file), the new file has the default ones.
  if (exists && S_ISREG(st.st_mode)) (void)::fchmod(fd, st.st_mode & 07777);
  file_ = fdopen(fd, "wb");
  if (file_ == nullptr) {
    Status s = errno_error("cannot open temporary output file", temp_path_);
    ::close(fd);
    std::remove(temp_path_);
    unregister_temp_path(&slot_);
    temp_path_[0] = '\0';
    return s;
  }
  return Status::ok();
}

ByteSink AtomicFile::sink() {
  ByteSink s;
  s.write = &AtomicFile::write;
  s.seek = &AtomicFile::seek;
  s.user = this;
  s.name = path_;
  return s;
}

// The bytes written; each MiB past the last one started has its writeback started (Linux), so
// that commit()'s fsync has less to wait for. Where that is not offered, or fails, the fsync
// does it all, as before (the bytes are the same either way).
bool AtomicFile::write(void* self, const uint8_t* data, size_t bytes) {
  AtomicFile* f = static_cast<AtomicFile*>(self);
  if (std::fwrite(data, 1, bytes, f->file_) != bytes) return f->write_failed();
#ifdef SYNC_FILE_RANGE_WRITE
  const off_t at = ftello(f->file_);
  if (at > 0 && static_cast<uint64_t>(at) > f->started_ &&
      static_cast<uint64_t>(at) - f->started_ >= kWritebackStep) {
    if (std::fflush(f->file_) != 0) return f->write_failed();
    const uint64_t from = f->started_;
    (void)sync_file_range(fileno(f->file_), static_cast<off_t>(from),
                          static_cast<off_t>(static_cast<uint64_t>(at) - from),
                          SYNC_FILE_RANGE_WRITE);
    f->started_ = static_cast<uint64_t>(at);
  }
#endif
  return true;
}

bool AtomicFile::write_failed() {
  if (write_errno_ == 0) write_errno_ = errno != 0 ? errno : EIO;
  return false;
}

Status AtomicFile::with_write_cause(Status s) const {
  if (write_errno_ != 0 && s.code() == StatusCode::kIoError) {
    s.append(": ").append(std::strerror(write_errno_));
  }
  return s;
}

bool AtomicFile::seek(void* self, uint64_t offset) {
  AtomicFile* f = static_cast<AtomicFile*>(self);
  if (offset > static_cast<uint64_t>(INT64_MAX)) return false;
  // (A pipe cannot seek: ESPIPE, "Illegal seek", then becomes the write's cause.)
  return fseeko(f->file_, static_cast<off_t>(offset), SEEK_SET) == 0 || f->write_failed();
}

Status AtomicFile::sync_in_background() {
  if (file_ == nullptr || syncer_.joinable()) {
    return Status::error(StatusCode::kInvalidArgument, "no open output file to sync");
  }
  if (std::fflush(file_) != 0) {
    Status s = errno_error("cannot write output file", path_);
    abort();
    return s;
  }
  if (direct_) return Status::ok();  // (a device or a pipe: no disk to sync)
  const int fd = fileno(file_);
  syncer_ = std::thread([this, fd] { sync_errno_ = fsync(fd) == 0 ? 0 : errno; });
  return Status::ok();
}

Status AtomicFile::finish() {
  if (file_ == nullptr) return Status::error(StatusCode::kInvalidArgument, "no open output file");
  bool ok;
  int saved;
  if (syncer_.joinable()) {  // flushed and syncing (sync_in_background)
    syncer_.join();
    ok = sync_errno_ == 0;
    saved = sync_errno_;
  } else {
    ok = std::fflush(file_) == 0 && (direct_ || fsync(fileno(file_)) == 0);
    saved = errno;
  }
  ok = (std::fclose(file_) == 0) && ok;
  file_ = nullptr;
  if (!ok) {
    errno = saved;
    Status s = errno_error("cannot write output file", path_);
    abort();
    return s;
  }
  return Status::ok();
}

Status AtomicFile::commit() {
  if (file_ != nullptr) SPLINTCORE_RETURN_IF_ERROR(finish());
  if (direct_) {  // written in place: nothing to rename
    direct_ = false;
    return Status::ok();
  }
  if (temp_path_[0] == '\0') {
    return Status::error(StatusCode::kInvalidArgument, "no open output file");
  }
  if (std::rename(temp_path_, path_) != 0) {
    Status s = errno_error("cannot move the output into place", path_);
    abort();
    return s;
  }
  unregister_temp_path(&slot_);
  temp_path_[0] = '\0';
  return Status::ok();
}

void AtomicFile::abort() {
  if (syncer_.joinable()) syncer_.join();
  if (file_ != nullptr) {
    std::fclose(file_);
    file_ = nullptr;
  }
  direct_ = false;
  if (temp_path_[0] != '\0') {
    std::remove(temp_path_);
    unregister_temp_path(&slot_);
    temp_path_[0] = '\0';
  }
}

Status read_file(Arena& arena, const char* path, uint64_t max_bytes, Span<uint8_t>* out) {
  FileSource file;
  SPLINTCORE_RETURN_IF_ERROR(file.open(path));
  ByteSource src = file.source();
  if (src.size == kUnknownSize) {
    return make_error(StatusCode::kUnsupported, "not a regular file").in_file(path);
  }
  if (src.size > max_bytes) {
    return make_error(StatusCode::kLimitExceeded, "file is ", src.size,
                      " bytes, over the limit of ", max_bytes)
        .in_file(path);
  }
  uint8_t* data = arena.allocate_array<uint8_t>(static_cast<size_t>(src.size));
  if (data == nullptr) return arena.exhausted_status();
  uint64_t got = 0;
  while (got < src.size) {
    int64_t n = src.read(src.user, data + got, static_cast<size_t>(src.size - got));
    if (n < 0) return make_error(StatusCode::kIoError, "read failed").in_file(path).at_byte(got);
    if (n == 0) {
      return make_error(StatusCode::kTruncated, "file shrank while reading")
          .in_file(path)
          .at_byte(got);
    }
    got += static_cast<uint64_t>(n);
  }
  *out = Span<uint8_t>(data, static_cast<size_t>(src.size));
  return Status::ok();
}

}  // namespace splintcore
