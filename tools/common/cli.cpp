#include "cli.h"

#include "splintcore/json.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <ctime>

namespace splintcore {
namespace cli {

bool parse_unsigned(const char* text, uint64_t* out) {
  if (text == nullptr || *text == '\0') return false;
  const char* end = text + std::strlen(text);
  auto r = std::from_chars(text, end, *out);
  return r.ec == std::errc() && r.ptr == end;
}

bool parse_size(const char* text, uint64_t* out) { return parse_byte_size(text, out); }

namespace {

// One value as the library's JsonWriter writes it (json.h): the CLI's objects and report.json
// share one escaping and one number format.
template <class T>
std::string json_value(const T& value) {
  std::string out;
  JsonWriter w(string_sink(&out));
  w.add(nullptr, value);
  (void)w.finish();  // a string sink never refuses bytes
  return out;
}

}  // namespace

std::string json_escape(const char* text) { return json_value(text != nullptr ? text : ""); }

ByteSink string_sink(std::string* out) {
  ByteSink sink;
  sink.write = [](void* user, const uint8_t* data, size_t bytes) {
    static_cast<std::string*>(user)->append(reinterpret_cast<const char*>(data), bytes);
    return true;
  };
  sink.user = out;
  sink.name = "memory";
  return sink;
}

std::string json_number(double value) { return json_value(value); }

void JsonObject::key(const char* k) {
  if (!body_.empty()) body_ += ",";
  body_ += json_escape(k) + ":";
}
void JsonObject::add(const char* k, const char* value) {
  key(k);
  body_ += json_escape(value);
}
void JsonObject::add(const char* k, bool value) {
  key(k);
  body_ += json_value(value);
}
void JsonObject::add(const char* k, uint64_t value) {
  key(k);
  body_ += json_value(value);
}
void JsonObject::add(const char* k, int64_t value) {
  key(k);
  body_ += json_value(value);
}
void JsonObject::add(const char* k, double value) {
  key(k);
  body_ += json_value(value);
}
void JsonObject::add(const char* k, const Vec3& v) {
  key(k);
  body_ += json_value(v);
}
void JsonObject::add_raw(const char* k, const std::string& json) {
  key(k);
  body_ += json;
}

void JsonObject::add_status(const Status& s) {
  add("status", status_code_name(s.code()));
  if (s.is_ok()) return;
  add("message", s.message());
  if (s.file()[0] != '\0') add("file", s.file());
  if (s.byte_offset() != kNoPosition) add("byte_offset", s.byte_offset());
  if (s.line() != kNoPosition) add("line", s.line());
  if (s.column() != kNoPosition) add("column", s.column());
  if (s.index() != kNoPosition) add("index", s.index());
}

std::string printable(const char* text) {
  std::string out;
  for (const unsigned char* p = reinterpret_cast<const unsigned char*>(text); *p != 0; ++p) {
    const bool c1 = p[0] == 0xC2 && p[1] >= 0x80 && p[1] <= 0x9F;
    if (p[0] >= 0x20 && p[0] != 0x7F && !c1) {
      out += static_cast<char>(p[0]);
      continue;
    }
    const int bytes = c1 ? 2 : 1;
    for (int k = 0; k < bytes; ++k) {
      static const char kHex[] = "0123456789abcdef";
      out += "\\x";
      out += kHex[p[k] >> 4];
      out += kHex[p[k] & 15];
    }
    p += bytes - 1;
  }
  return out;
}

void print_error(const Status& status) {
  char text[512];
  status.format(text, sizeof(text));
  std::fprintf(stderr, "splintcore: error: %s\n", printable(text).c_str());
}

Status read_whole_file(const std::string& path, uint64_t max_bytes, std::vector<uint8_t>* out) {
  out->clear();
  // Regular files: the size from stat. Others (pipes): more than the limit arrived.
  auto too_big = [&](uint64_t size, bool known) {
    Status s = known ? make_error(StatusCode::kLimitExceeded, "file is ", size, " bytes,")
                     : make_error(StatusCode::kLimitExceeded, "file is");
    return s.append(" over the limit of ")
        .append_u64(max_bytes)
        .append(" bytes (--max-input-bytes raises it)")
        .in_file(path.c_str());
  };
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    return make_error(StatusCode::kIoError, "cannot open the file: ", std::strerror(errno))
        .in_file(path.c_str());
  }
  if (S_ISDIR(st.st_mode)) {
    return make_error(StatusCode::kUnsupported, "is a directory, not a file").in_file(path.c_str());
  }
  if (S_ISREG(st.st_mode) && static_cast<uint64_t>(st.st_size) > max_bytes) {
    return too_big(static_cast<uint64_t>(st.st_size), true);
  }
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) {
    return make_error(StatusCode::kIoError, "cannot open the file: ", std::strerror(errno))
        .in_file(path.c_str());
  }
  if (S_ISREG(st.st_mode)) out->reserve(static_cast<size_t>(st.st_size));
  std::vector<uint8_t> buffer(size_t{1} << 16);
  size_t n = 0;
  bool over = false;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), f)) > 0) {
    if (n > max_bytes - out->size()) {  // out->size() <= max_bytes here
      over = true;
      break;
    }
    out->insert(out->end(), buffer.data(), buffer.data() + n);
  }
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (over) {
    out->clear();
    return too_big(0, false);
  }
  if (failed) {
    out->clear();
    return make_error(StatusCode::kIoError, "read failed").in_file(path.c_str());
  }
  return Status::ok();
}

bool read_whole_file(const std::string& path, std::vector<uint8_t>* out) {
  return read_whole_file(path, kMaxMeshBytes, out).is_ok();
}

Status OutputSet::keep(std::unique_ptr<AtomicFile> file) {
  SPLINTCORE_RETURN_IF_ERROR(file->finish());
  std::lock_guard<std::mutex> lock(mutex_);
  files_.push_back(std::move(file));
  return Status::ok();
}

Status OutputSet::place(std::unique_ptr<AtomicFile> file, OutputSet* set) {
  if (set != nullptr) return set->keep(std::move(file));
  return file->commit();
}

namespace {

// Exclusive flock()s on the folders of a set's destinations, taken in name order (so two sets
// that share folders cannot wait on each other) and released by the destructor. A folder that
// cannot be opened or locked is left unlocked: its rename then says what is wrong. A lock held
// elsewhere is waited for, polled every 10 ms: after a second the wait is said on stderr, and
// past `wait_seconds` it is an error naming the folder (a run stopped while it renames, with
// Ctrl-Z, would otherwise keep every later run waiting without a word).
class FolderLocks {
 public:
  FolderLocks() = default;
  Status take(std::vector<std::string> folders, double wait_seconds) {
    std::sort(folders.begin(), folders.end());
    folders.erase(std::unique(folders.begin(), folders.end()), folders.end());
    for (const std::string& folder : folders) {
      const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
      if (fd < 0) continue;
      fds_.push_back(fd);
      SPLINTCORE_RETURN_IF_ERROR(wait_for(fd, folder, wait_seconds));
    }
    return Status::ok();
  }
  ~FolderLocks() {
    for (const int fd : fds_) ::close(fd);  // closing releases the lock
  }
  FolderLocks(const FolderLocks&) = delete;
  FolderLocks& operator=(const FolderLocks&) = delete;

 private:
  static Status wait_for(int fd, const std::string& folder, double wait_seconds) {
    const double start = monotonic_seconds();
    bool told = false;
    for (;;) {
      if (::flock(fd, LOCK_EX | LOCK_NB) == 0) return Status::ok();
      if (errno == EINTR) continue;
      if (errno != EWOULDBLOCK) return Status::ok();  // no lock here: the renames go on
      const double waited = monotonic_seconds() - start;
      if (waited >= wait_seconds) {
        return make_error(StatusCode::kIoError,
                          "cannot place the outputs: another process has held this folder's "
                          "lock for ",
                          static_cast<uint64_t>(waited),
                          " s (a splintcore run stopped while it "
                          "renames its files?); nothing of this run was placed")
            .in_file(folder.c_str());
      }
      if (!told && waited >= 1.0) {
        std::fprintf(stderr, "splintcore: waiting for %s: another run is placing its files there\n",
                     printable(folder.c_str()).c_str());
        told = true;
      }
      struct timespec pause = {0, 10 * 1000 * 1000};
      ::nanosleep(&pause, nullptr);
    }
  }

  std::vector<int> fds_;
};

std::string folder_of(const char* path) {
  const char* slash = std::strrchr(path, '/');
  if (slash == nullptr) return ".";
  if (slash == path) return "/";
  return std::string(path, static_cast<size_t>(slash - path));
}

}  // namespace

Status OutputSet::commit() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<std::string> folders;
  for (const std::unique_ptr<AtomicFile>& f : files_)
    folders.push_back(folder_of(f->destination()));
  FolderLocks locks;  // one run's renames at a time in a folder
  SPLINTCORE_RETURN_IF_ERROR(locks.take(std::move(folders), lock_wait_seconds_));
  for (const std::unique_ptr<AtomicFile>& f : files_) {
    struct stat st;
    if (::stat(f->destination(), &st) == 0 && S_ISDIR(st.st_mode)) {
      return Status::error(StatusCode::kIoError,
                           "cannot move the output into place: a folder has its name")
          .in_file(f->destination());
    }
  }
  for (const std::unique_ptr<AtomicFile>& f : files_) SPLINTCORE_RETURN_IF_ERROR(f->commit());
  files_.clear();
  return Status::ok();
}

Status write_bytes_atomically(const std::string& path, std::initializer_list<ByteSpan> parts,
                              OutputSet* set) {
  auto file = std::make_unique<AtomicFile>();
  SPLINTCORE_RETURN_IF_ERROR(file->open(path.c_str()));
  const ByteSink sink = file->sink();
  for (const ByteSpan& part : parts) {
    if (part.size != 0 &&
        !sink.write(sink.user, static_cast<const uint8_t*>(part.data), part.size)) {
      // (~AtomicFile removes the temporary file.)
      return file->with_write_cause(
          Status::error(StatusCode::kIoError, "cannot write").in_file(path.c_str()));
    }
  }
  return OutputSet::place(std::move(file), set);
}

Status write_bytes_atomically(const std::string& path, const void* data, size_t size,
                              OutputSet* set) {
  return write_bytes_atomically(path, {ByteSpan{data, size}}, set);
}

Status write_bytes_atomically(const std::string& path, const std::string& bytes, OutputSet* set) {
  return write_bytes_atomically(path, {ByteSpan{bytes.data(), bytes.size()}}, set);
}

}  // namespace cli
}  // namespace splintcore
