// The OpenMP thread count of the calling thread's parallel regions, set for a scope and put back
// after it: a mapper nodelet's ~threads, applied to each frame on whichever of the nodelet
// manager's worker threads (shared by every nodelet) integrates it.
#pragma once

namespace occupancy_fusion {

class ScopedOpenMpThreads {
 public:
  // threads > 0: parallel regions started by this thread in the scope use that many threads;
  // 0 (or less) changes nothing.
  explicit ScopedOpenMpThreads(int threads);
  ~ScopedOpenMpThreads();
  ScopedOpenMpThreads(const ScopedOpenMpThreads&) = delete;
  ScopedOpenMpThreads& operator=(const ScopedOpenMpThreads&) = delete;

 private:
  int previous_ = 0;  // the count before the scope; 0: nothing was changed
};

}  // namespace occupancy_fusion
