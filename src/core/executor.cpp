// The serial executor and the parallel_for entry point. Threaded executors live in
// platform/ (hosted) or are supplied by the embedder.
#include "splintcore/core.h"

namespace splintcore {

namespace {
void run_serial(void*, uint32_t count, TaskFunction task, void* context) {
  for (uint32_t i = 0; i < count; ++i) task(context, i);
}
constexpr Executor kSerial{run_serial, nullptr, 1};
}  // namespace

const Executor& serial_executor() { return kSerial; }

void parallel_for(const Executor* executor, uint32_t count, TaskFunction task, void* context) {
  if (count == 0) return;
  if (executor == nullptr || executor->run == nullptr || count == 1) {
    run_serial(nullptr, count, task, context);
    return;
  }
  executor->run(executor->self, count, task, context);
}

}  // namespace splintcore
