#pragma once
// Counts heap allocations (and their bytes) made by the calling thread, to prove a hot loop allocates nothing.
// Linking tests/common/counting_new.cc into a test binary replaces global operator new there;
// counting is off until a scope asks for it.
namespace pcisim::testing {

class AllocationCount {
 public:
  AllocationCount();   // starts counting this thread's allocations
  ~AllocationCount();  // stops
  long allocations() const;
  long long bytes() const;    // asked for in all
  long long largest() const;  // the biggest single request
};

}  // namespace pcisim::testing
