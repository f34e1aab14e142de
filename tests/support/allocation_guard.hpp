// Counts heap allocations made by the current thread while a guard is alive, so a test can prove a
// real-time path never allocates (in the way Drake's LimitMalloc does):
//
//   deflex::test::AllocationGuard guard;
//   step(...);
//   EXPECT_EQ(guard.allocations(), 0);
#pragma once

#include <cstddef>

namespace deflex::test {

class AllocationGuard {
 public:
  AllocationGuard();
  ~AllocationGuard();
  AllocationGuard(const AllocationGuard&) = delete;
  AllocationGuard& operator=(const AllocationGuard&) = delete;

  /// Number of operator new / malloc-family calls on this thread since construction.
  [[nodiscard]] std::size_t allocations() const;

 private:
  std::size_t start_;
  bool was_active_;
};

/// Total allocations counted on this thread while any guard was active.
std::size_t counted_allocations();

}  // namespace deflex::test
