// Independent tasks on a few threads, for the library's parallel loops
// (diagnose's candidate fits, the refinement's friction screen): no pool
// outlives the call and no exception escapes a thread.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace pneumaid::internal {

// Runs `tasks` on up to `threads` threads (the calling one among them); the
// first exception a task threw is rethrown here, after every thread has
// joined.
inline void RunAll(std::vector<std::function<void()>>* tasks, int threads) {
  std::atomic<std::size_t> next{0};
  std::mutex failure_mutex;
  std::exception_ptr failure;
  const auto worker = [&] {
    for (std::size_t i = next++; i < tasks->size(); i = next++) {
      try {
        (*tasks)[i]();
      } catch (...) {
        std::lock_guard<std::mutex> lock(failure_mutex);
        if (!failure) failure = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  const int extra = std::min<int>(threads, static_cast<int>(tasks->size())) - 1;
  for (int t = 0; t < extra; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
}

}  // namespace pneumaid::internal
