// The allocation count of the link benchmarks: a replacement operator new that counts, while
// g_counting is set, every allocation of the program (all threads). Include it in exactly one
// translation unit of a benchmark program (each bench/*_bench.cpp is one).
#pragma once

#include <atomic>
#include <cstdlib>
#include <new>

// GCC sees the replacement operator new (malloc) and delete (free) of this file inlined into the same
// translation unit and calls them mismatched; they are the standard replacement pair.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

namespace {
std::atomic<bool> g_counting{false};
std::atomic<std::size_t> g_allocations{0};
}  // namespace

void* operator new(std::size_t size) {
  if (g_counting.load(std::memory_order_relaxed)) {
    g_allocations.fetch_add(1, std::memory_order_relaxed);
  }
  if (void* p = std::malloc(size == 0 ? 1 : size)) {
    return p;
  }
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
