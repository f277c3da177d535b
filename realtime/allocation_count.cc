#include "realtime/allocation_count.h"

#include <cstdlib>
#include <new>

namespace {
thread_local bool g_counting = false;
thread_local long g_allocations = 0;
thread_local long long g_bytes = 0, g_largest = 0;
}  // namespace

void* operator new(std::size_t n) {
  if (g_counting) {
    ++g_allocations;
    g_bytes += static_cast<long long>(n);
    if (static_cast<long long>(n) > g_largest) g_largest = static_cast<long long>(n);
  }
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
  return operator new(n);
}
// the nothrow forms too (std::stable_sort's temporary buffer takes one): every new here is malloc's,
// so every delete may free it (a sanitizer's own nothrow new, freed here, is a mismatch)
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return operator new(n);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept {
  return operator new(n, std::nothrow);
}
void operator delete(void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}

namespace pcisim::realtime {

AllocationCount::AllocationCount() {
  g_allocations = 0;
  g_bytes = g_largest = 0;
  g_counting = true;
}
AllocationCount::~AllocationCount() {
  g_counting = false;
}
long AllocationCount::allocations() const {
  return g_allocations;
}
long long AllocationCount::bytes() const {
  return g_bytes;
}
long long AllocationCount::largest() const {
  return g_largest;
}

}  // namespace pcisim::realtime
