// Batches of the deflex module spread over threads: rows [0, n) cut into one contiguous block a
// thread, each thread with its own scratch (a Workspace), the GIL released by the caller. A thread's
// exception is kept and the first one thrown again once every thread has joined.
#pragma once

#include <algorithm>
#include <cstddef>
#include <exception>
#include <thread>
#include <vector>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex::python {

/// Rows a thread takes at least: below this a thread's start (about 20 us) costs more than it saves.
inline constexpr std::ptrdiff_t kRowsPerThread = 256;
/// Rows a per-configuration call holds the GIL for at most (about 0.1 us of C++ each): releasing and
/// taking it back costs a few tenths of a microsecond, the whole of a single call's work.
inline constexpr std::ptrdiff_t kGilRows = 16;

/// The cores of this machine, counted once: std::thread::hardware_concurrency() reads
/// /sys/devices/system/cpu/online on every call (glibc), 10-19 us on the build host, which a single
/// fk() paid on every call (bench/python_call_bench.py).
inline int machine_cores() {
  static const int cores = static_cast<int>(std::max(1U, std::thread::hardware_concurrency()));
  return cores;
}

/// The threads a batch of `rows` uses: `requested` (0: every core), at most one per kRowsPerThread
/// rows, at least one. Negative or huge requests are an InputError.
inline int batch_threads(int requested, std::ptrdiff_t rows) {
  if (requested < 0 || requested > 1024) {
    throw InputError(fmt::format("argument threads: must be 0 (every core) to 1024, got {}", requested));
  }
  const auto by_rows = static_cast<int>(std::max<std::ptrdiff_t>(1, rows / kRowsPerThread));
  if (by_rows == 1) return 1;  // a single configuration or a small batch: this thread alone
  const int wanted = requested == 0 ? machine_cores() : requested;
  return std::max(1, std::min(wanted, by_rows));
}

/// Runs block(begin, end) on `threads` threads over [0, rows) (the calling thread takes the first block).
template <typename Block>
void parallel_rows(std::ptrdiff_t rows, int threads, Block&& block) {
  if (threads <= 1 || rows <= 1) {
    block(std::ptrdiff_t{0}, rows);
    return;
  }
  std::vector<std::exception_ptr> errors(static_cast<std::size_t>(threads));
  std::vector<std::thread> pool;
  pool.reserve(static_cast<std::size_t>(threads - 1));
  const auto run = [&](int t) {
    const std::ptrdiff_t begin = rows * t / threads, end = rows * (t + 1) / threads;
    try {
      block(begin, end);
    } catch (...) {
      errors[static_cast<std::size_t>(t)] = std::current_exception();
    }
  };
  for (int t = 1; t < threads; ++t) pool.emplace_back(run, t);
  run(0);
  for (std::thread& th : pool) th.join();
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }
}

}  // namespace deflex::python
