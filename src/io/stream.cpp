// Byte sources and sinks over memory, and a hashing sink.
#include "io/mesh_text.h"
#include "splintcore/io.h"

namespace splintcore {

namespace {
int64_t memory_read(void* user, uint8_t* buffer, size_t capacity) {
  MemorySource* s = static_cast<MemorySource*>(user);
  uint64_t left = s->size - s->position;
  uint64_t take = capacity < left ? capacity : left;
  if (s->max_chunk > 0 && take > s->max_chunk) take = s->max_chunk;
  if (take > 0) std::memcpy(buffer, s->data + s->position, static_cast<size_t>(take));
  s->position += take;
  return static_cast<int64_t>(take);
}

bool memory_write(void* user, const uint8_t* data, size_t bytes) {
  MemorySink* s = static_cast<MemorySink*>(user);
  if (bytes > s->capacity || s->position > s->capacity - bytes) return false;
  if (bytes > 0) std::memcpy(s->data + s->position, data, bytes);
  s->position += bytes;
  if (s->position > s->size) s->size = s->position;
  return true;
}

bool memory_seek(void* user, uint64_t offset) {
  MemorySink* s = static_cast<MemorySink*>(user);
  if (offset > s->size) return false;
  s->position = offset;
  return true;
}

bool hash_write(void* user, const uint8_t* data, size_t bytes) {
  HashSink* s = static_cast<HashSink*>(user);
  s->sha.update(data, bytes);
  s->size += bytes;
  return s->next.write == nullptr || s->next.write(s->next.user, data, bytes);
}
}  // namespace

ByteSource memory_source(MemorySource* state, const char* name) {
  ByteSource source;
  source.read = memory_read;
  source.user = state;
  source.size = state->size;
  source.name = name;
  return source;
}

namespace meshio {
const uint8_t* take_memory_bytes(const ByteSource& source, uint64_t consumed) {
  if (source.read != memory_read) return nullptr;
  MemorySource* s = static_cast<MemorySource*>(source.user);
  if (s->max_chunk != 0 || s->size != source.size || s->position != consumed ||
      consumed > s->size) {
    return nullptr;
  }
  s->position = s->size;
  return s->data;
}
}  // namespace meshio

ByteSink memory_sink(MemorySink* state, const char* name) {
  ByteSink sink;
  sink.write = memory_write;
  sink.seek = memory_seek;
  sink.user = state;
  sink.name = name;
  return sink;
}

ByteSink hash_sink(HashSink* state) {
  ByteSink sink;
  sink.write = hash_write;
  sink.user = state;
  sink.name = state->next.name != nullptr ? state->next.name : "sha256";
  return sink;
}

}  // namespace splintcore
