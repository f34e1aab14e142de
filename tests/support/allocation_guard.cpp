// Replacement global operator new/delete that count allocations per thread while a guard is active.
#include "support/allocation_guard.hpp"

#include <cstdlib>
#include <new>

namespace {
thread_local std::size_t g_count = 0;
thread_local int g_active = 0;

void* counted_alloc(std::size_t size, std::size_t align) {
  if (g_active > 0) {
    ++g_count;
  }
  if (size == 0) {
    size = 1;
  }
  void* p = nullptr;
  if (align > alignof(std::max_align_t)) {
    if (posix_memalign(&p, align, size) != 0) {
      p = nullptr;
    }
  } else {
    p = std::malloc(size);
  }
  return p;
}
}  // namespace

namespace deflex::test {
AllocationGuard::AllocationGuard() : start_(g_count), was_active_(g_active > 0) { ++g_active; }
AllocationGuard::~AllocationGuard() { --g_active; }
std::size_t AllocationGuard::allocations() const { return g_count - start_; }
std::size_t counted_allocations() { return g_count; }
}  // namespace deflex::test

void* operator new(std::size_t size) {
  void* p = counted_alloc(size, alignof(std::max_align_t));
  if (p == nullptr) {
    throw std::bad_alloc();
  }
  return p;
}
void* operator new[](std::size_t size) { return operator new(size); }
void* operator new(std::size_t size, std::align_val_t align) {
  void* p = counted_alloc(size, static_cast<std::size_t>(align));
  if (p == nullptr) {
    throw std::bad_alloc();
  }
  return p;
}
void* operator new[](std::size_t size, std::align_val_t align) { return operator new(size, align); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  return counted_alloc(size, alignof(std::max_align_t));
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  return counted_alloc(size, alignof(std::max_align_t));
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
