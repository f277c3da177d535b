#pragma once
// Counts heap allocations (and their bytes) made by the calling thread, to prove a hot loop allocates nothing.
// Linking the object library pcisim_allocation_count (realtime/allocation_count.cc, kept out of
// pcisim_realtime so no program gets it by accident) into a test or benchmark binary replaces
// global operator new there; counting is off until a scope asks for it.
namespace pcisim::realtime {

class AllocationCount {
 public:
  AllocationCount();   // starts counting this thread's allocations
  ~AllocationCount();  // stops
  long allocations() const;
  long long bytes() const;    // asked for in all
  long long largest() const;  // the biggest single request
};

}  // namespace pcisim::realtime
