#include "files.h"

#include <algorithm>
#include <memory>

namespace splintcore {
namespace tool {

BackgroundHasher::BackgroundHasher(Sha256* sha) : sha_(sha) {
  for (std::vector<uint8_t>& slot : slot_) slot.reserve(kSlotBytes);
  thread_ = std::thread([this] { run(); });
}

BackgroundHasher::~BackgroundHasher() { finish(); }

void BackgroundHasher::add(const uint8_t* data, size_t bytes) {
  while (bytes > 0) {
    std::vector<uint8_t>& slot = slot_[fill_];
    const size_t n = std::min(bytes, kSlotBytes - slot.size());
    slot.insert(slot.end(), data, data + n);
    data += n;
    bytes -= n;
    if (slot.size() == kSlotBytes) publish();
  }
}

void BackgroundHasher::publish() {
  std::unique_lock<std::mutex> lock(mutex_);
  ++ready_;
  changed_.notify_all();
  changed_.wait(lock, [this] { return ready_ < kSlots; });  // the next slot is free
  fill_ = (fill_ + 1) % kSlots;
}

void BackgroundHasher::finish() {
  if (!thread_.joinable()) return;
  if (!slot_[fill_].empty()) publish();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    finishing_ = true;
  }
  changed_.notify_all();
  thread_.join();
}

void BackgroundHasher::run() {
  size_t next = 0;  // the oldest published slot
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      changed_.wait(lock, [this] { return ready_ > 0 || finishing_; });
      if (ready_ == 0) return;  // finishing, all hashed
    }
    std::vector<uint8_t>& slot = slot_[next];
    sha_->update(slot.data(), slot.size());
    slot.clear();
    next = (next + 1) % kSlots;
    std::lock_guard<std::mutex> lock(mutex_);
    --ready_;
    changed_.notify_all();
  }
}

Status InputFile::open(const char* path, uint64_t max_bytes) {
  path_ = path;
  max_bytes_ = max_bytes;
  count_ = 0;
  over_limit_ = false;
  SPLINTCORE_RETURN_IF_ERROR(file_.open(path));
  inner_ = file_.source();
  if (inner_.size != kUnknownSize && inner_.size > max_bytes) {
    file_.close();
    return limit_status(inner_.size);
  }
  return Status::ok();
}

Status InputFile::limit_status(uint64_t size) const {
  Status s = size != kUnknownSize
                 ? make_error(StatusCode::kLimitExceeded, "file is ", size, " bytes,")
                 : make_error(StatusCode::kLimitExceeded, "file is");
  return s.append(" over the limit of ")
      .append_u64(max_bytes_)
      .append(" bytes (--max-input-bytes raises it)")
      .in_file(path_.c_str());
}

int64_t InputFile::read(void* user, uint8_t* buffer, size_t capacity) {
  InputFile* self = static_cast<InputFile*>(user);
  const int64_t n = self->inner_.read(self->inner_.user, buffer, capacity);
  if (n <= 0) return n;
  if (static_cast<uint64_t>(n) > self->max_bytes_ - self->count_) {  // count_ <= max_bytes_
    self->over_limit_ = true;
    return -1;
  }
  self->count_ += static_cast<uint64_t>(n);
  if (self->sha_ != nullptr) self->sha_->update(buffer, static_cast<size_t>(n));
  if (self->hasher_ != nullptr) self->hasher_->add(buffer, static_cast<size_t>(n));
  return n;
}

ByteSource InputFile::source() {
  ByteSource s = inner_;
  s.read = &InputFile::read;
  s.user = this;
  return s;
}

Status InputFile::read_all(std::vector<uint8_t>* out) {
  out->clear();
  if (inner_.size != kUnknownSize) out->reserve(static_cast<size_t>(inner_.size));
  std::vector<uint8_t> buffer(size_t{1} << 16);
  int64_t n = 0;
  while ((n = read(this, buffer.data(), buffer.size())) > 0) {
    out->insert(out->end(), buffer.data(), buffer.data() + n);
  }
  if (n < 0) {
    out->clear();
    if (over_limit_) return limit_status(kUnknownSize);
    return make_error(StatusCode::kIoError, "read failed").in_file(path_.c_str());
  }
  return Status::ok();
}

Status InputFile::read_rest() {
  uint8_t buffer[4096];
  int64_t n = 0;
  while ((n = read(this, buffer, sizeof(buffer))) > 0) {
  }
  if (n == 0) return Status::ok();
  if (over_limit_) return limit_status(kUnknownSize);
  return make_error(StatusCode::kIoError, "read failed").in_file(path_.c_str());
}

Status read_mesh_file(const Context& ctx, const char* path, uint64_t max_bytes, bool hash,
                      Mesh* mesh, MeshFileInfo* info) {
  InputFile file;
  SPLINTCORE_RETURN_IF_ERROR(file.open(path, max_bytes));
  Sha256 sha;
  // With more than one thread the file is hashed beside the reading (the same digest).
  const bool beside = hash && ctx.executor != nullptr && ctx.executor->concurrency > 1;
  std::unique_ptr<BackgroundHasher> hasher;
  if (beside) {
    hasher.reset(new BackgroundHasher(&sha));
    file.hash_into(hasher.get());
  } else if (hash) {
    file.hash_into(&sha);
  }
  MeshReadOptions options;
  options.weld = true;
  MeshReadInfo read;
  Status s = read_mesh(ctx, file.source(), options, mesh, &read);
  if (s.is_ok() && hash) s = file.read_rest();
  if (hasher != nullptr) hasher->finish();
  if (file.went_over_limit()) return file.limit_status(kUnknownSize);
  SPLINTCORE_RETURN_IF_ERROR(s);
  if (info != nullptr) {
    info->format = read.format;
    info->triangles = read.triangles;
    info->bytes = read.bytes;
    if (hash) {
      uint8_t digest[32];
      sha.finish(digest);
      char hex[65];
      Sha256::to_hex(digest, hex);
      info->sha256 = hex;
    }
  }
  return Status::ok();
}

namespace {

// The files read in tasks, each into its slice (read_mesh_files); false when they are to be read
// one after the other (the arena then as it was). *status: the first file's error, in order.
bool read_in_slices(const Context& ctx, const std::vector<const char*>& paths, uint64_t max_bytes,
                    bool hash, std::vector<Mesh>* out, std::vector<MeshFileInfo>* infos,
                    Status* status) {
  const size_t n = paths.size();
  std::vector<uint64_t> sizes(n);
  uint64_t total = 0;
  for (size_t i = 0; i < n; ++i) {
    FileSource f;
    if (!f.open(paths[i]).is_ok()) return false;  // its error comes from the serial read
    sizes[i] = f.source().size;
    if (sizes[i] == kUnknownSize || sizes[i] > max_bytes) return false;
    total += sizes[i];
  }
  Arena& arena = *ctx.arena;
  constexpr size_t kAlign = 64;
  const size_t high_before = arena.high_water(), used_before = arena.used();
  // Each slice: 1 MiB for what any file needs (the reader's 64 KiB buffer, a small weld table),
  // then a share of the rest by size.
  constexpr size_t kFixed = size_t{1} << 20;
  const size_t spare = n * (kAlign + kFixed) + kAlign;
  if (total == 0 || arena.cap() - used_before <= spare) return false;
  const size_t free_bytes = arena.cap() - used_before - spare;
  std::vector<size_t> slice(n);
  size_t all = 0;
  for (size_t i = 0; i < n; ++i) {
    // free * size / total without overflow (sizes and the cap are below 2^63).
    const double share = static_cast<double>(sizes[i]) / static_cast<double>(total);
    slice[i] =
        kFixed + static_cast<size_t>(static_cast<double>(free_bytes) * share) / kAlign * kAlign;
    all += slice[i];
  }
  const Arena::Marker start = arena.mark();
  auto* base = static_cast<unsigned char*>(arena.allocate(all, kAlign));
  if (base == nullptr) {
    arena.forget_failure();
    return false;
  }
  std::vector<std::unique_ptr<Arena>> arenas(n);
  std::vector<Mesh> meshes(n);
  std::vector<MeshFileInfo> found(n);
  std::vector<Status> statuses(n);
  size_t offset = 0;
  for (size_t i = 0; i < n; ++i) {
    arenas[i].reset(new Arena(base + offset, slice[i]));
    meshes[i].bind(arenas[i].get());
    offset += slice[i];
  }
  auto task = [&](uint32_t i) {
    const Context own(arenas[i].get());  // serial inside, no progress from a worker
    statuses[i] = read_mesh_file(own, paths[i], max_bytes, hash, &meshes[i], &found[i]);
  };
  parallel_for_each(ctx.executor, static_cast<uint32_t>(n), task);
  size_t peak = used_before;
  for (size_t i = 0; i < n; ++i) {
    if (statuses[i].code() == StatusCode::kArenaExhausted) {
      arena.rewind(start);
      arena.reset_high_water();
      arena.note_high_water(high_before);
      return false;
    }
    peak += arenas[i]->high_water();
  }
  arena.rewind(start);
  arena.reset_high_water();
  arena.note_high_water(high_before > peak ? high_before : peak);
  for (size_t i = 0; i < n; ++i) {
    if (!statuses[i].is_ok()) {
      *status = statuses[i];
      return true;
    }
  }
  // Down in order: each mesh lies in its slice, at or above where it goes.
  for (size_t i = 0; i < n; ++i) {
    const Mesh& m = meshes[i];
    const bool vertices_first =
        !m.vertices.empty() && !m.triangles.empty() &&
        static_cast<const void*>(m.vertices.data()) < static_cast<const void*>(m.triangles.data());
    move_mesh_down(arena, arena.mark(), m, &(*out)[i], vertices_first);
    if (infos != nullptr) (*infos)[i] = found[i];
  }
  *status = Status::ok();
  return true;
}

}  // namespace

Status read_mesh_files(const Context& ctx, const std::vector<const char*>& paths,
                       uint64_t max_bytes, bool hash, std::vector<Mesh>* out,
                       std::vector<MeshFileInfo>* infos, bool* in_tasks) {
  if (in_tasks != nullptr) *in_tasks = false;
  out->clear();
  out->resize(paths.size());
  for (Mesh& m : *out) m.bind(ctx.arena);
  if (infos != nullptr) {
    infos->clear();
    infos->resize(paths.size());
  }
  const bool threads = ctx.executor != nullptr && ctx.executor->concurrency > 1;
  Status s;
  if (paths.size() > 1 && threads && read_in_slices(ctx, paths, max_bytes, hash, out, infos, &s)) {
    if (in_tasks != nullptr) *in_tasks = true;
    return s;
  }
  for (size_t i = 0; i < paths.size(); ++i) {
    SPLINTCORE_RETURN_IF_ERROR(read_mesh_file(ctx, paths[i], max_bytes, hash, &(*out)[i],
                                              infos != nullptr ? &(*infos)[i] : nullptr));
  }
  return Status::ok();
}

Status read_whole_input(const char* path, uint64_t max_bytes, std::vector<uint8_t>* out) {
  out->clear();
  InputFile file;
  SPLINTCORE_RETURN_IF_ERROR(file.open(path, max_bytes));
  return file.read_all(out);
}

const char* encoding_name(MeshFormat format) {
  const bool text = format == MeshFormat::kStlAscii || format == MeshFormat::kPlyAscii ||
                    format == MeshFormat::kObj;
  return text ? "ascii" : "binary";
}

Status write_mesh_atomically(const Context& ctx, const Mesh& mesh, const char* path, bool ascii) {
  AtomicFile out;
  SPLINTCORE_RETURN_IF_ERROR(out.open(path));
  StlWriteOptions wo;
  wo.format = ascii ? StlFormat::kAscii : StlFormat::kBinary;
  SPLINTCORE_RETURN_IF_ERROR(write_stl(ctx, mesh, out.sink(), wo));  // ~AtomicFile cleans up
  return out.commit();
}

Status write_bytes_atomically(const std::string& path, const void* data, size_t size) {
  AtomicFile file;
  SPLINTCORE_RETURN_IF_ERROR(file.open(path.c_str()));
  ByteSink sink = file.sink();
  if (!sink.write(sink.user, static_cast<const uint8_t*>(data), size)) {
    return Status::error(StatusCode::kIoError, "cannot write").in_file(path.c_str());
  }
  return file.commit();
}

Status write_bytes_atomically(const std::string& path, const std::string& bytes) {
  return write_bytes_atomically(path, bytes.data(), bytes.size());
}

}  // namespace tool
}  // namespace splintcore
