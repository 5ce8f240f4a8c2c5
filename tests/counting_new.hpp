// Counting replacements of every global operator new/delete, for tests that prove a hot path
// allocates nothing. Include this header from exactly one .cpp of a test binary of its own: the
// replacements are ordinary (non-inline) definitions and affect the whole binary.
//
// An allocation is counted while counting is on (a CountAllocations scope, or start_counting())
// and, if counting was started for marked threads only, only on threads that called
// count_this_thread(true). Eigen's own aligned allocations go through malloc and are not seen
// here (tests/learning/mlp_alloc_test.cpp intercepts malloc for that).
#pragma once

#include <atomic>
#include <cstdlib>
#include <new>

namespace pamdp::testing::alloc {

inline std::atomic<bool> g_counting{false};
inline std::atomic<bool> g_only_marked{false};
inline std::atomic<long> g_allocations{0};
inline thread_local bool t_marked = false;

inline void count_this_thread(bool on) {
  t_marked = on;
}
inline void start_counting(bool only_marked_threads) {
  g_allocations = 0;
  g_only_marked = only_marked_threads;
  g_counting = true;
}
inline void stop_counting() {
  g_counting = false;
}
inline long allocations() {
  return g_allocations.load();
}

// Counts allocations made while it is alive (on every thread, or on marked threads only).
class CountAllocations {
 public:
  explicit CountAllocations(bool only_marked_threads = false) { start_counting(only_marked_threads); }
  ~CountAllocations() { stop_counting(); }
  CountAllocations(const CountAllocations&) = delete;
  CountAllocations& operator=(const CountAllocations&) = delete;
  [[nodiscard]] long count() const { return allocations(); }
};

inline void* counted_alloc(std::size_t size, std::size_t align) noexcept {
  if (g_counting.load(std::memory_order_relaxed) && (!g_only_marked.load(std::memory_order_relaxed) || t_marked)) {
    g_allocations.fetch_add(1, std::memory_order_relaxed);
  }
  if (size == 0) {
    size = 1;
  }
  if (align <= alignof(std::max_align_t)) {
    return std::malloc(size);
  }
  return std::aligned_alloc(align, (size + align - 1) / align * align);
}

inline void* alloc_or_throw(std::size_t size, std::size_t align) {
  void* p = counted_alloc(size, align);
  if (p == nullptr) {
    throw std::bad_alloc();
  }
  return p;
}

}  // namespace pamdp::testing::alloc

void* operator new(std::size_t size) {
  return pamdp::testing::alloc::alloc_or_throw(size, alignof(std::max_align_t));
}
void* operator new[](std::size_t size) {
  return pamdp::testing::alloc::alloc_or_throw(size, alignof(std::max_align_t));
}
void* operator new(std::size_t size, std::align_val_t align) {
  return pamdp::testing::alloc::alloc_or_throw(size, static_cast<std::size_t>(align));
}
void* operator new[](std::size_t size, std::align_val_t align) {
  return pamdp::testing::alloc::alloc_or_throw(size, static_cast<std::size_t>(align));
}
// libzmq allocates with new (std::nothrow); the matching deletes are below too.
void* operator new(std::size_t size, const std::nothrow_t& /*tag*/) noexcept {
  return pamdp::testing::alloc::counted_alloc(size, alignof(std::max_align_t));
}
void* operator new[](std::size_t size, const std::nothrow_t& /*tag*/) noexcept {
  return pamdp::testing::alloc::counted_alloc(size, alignof(std::max_align_t));
}
void operator delete(void* p, const std::nothrow_t& /*tag*/) noexcept {
  std::free(p);
}
void operator delete[](void* p, const std::nothrow_t& /*tag*/) noexcept {
  std::free(p);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t /*size*/) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t /*size*/) noexcept {
  std::free(p);
}
void operator delete(void* p, std::align_val_t /*align*/) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::align_val_t /*align*/) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t /*size*/, std::align_val_t /*align*/) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t /*size*/, std::align_val_t /*align*/) noexcept {
  std::free(p);
}
