#include "occupancy_fusion/mapping/scoped_openmp_threads.h"

#include <omp.h>

namespace occupancy_fusion {

// omp_set_num_threads sets nthreads-var, an internal control variable with data-environment scope:
// the calling thread's own, so other threads (and other nodelets' callbacks on them) keep theirs.
ScopedOpenMpThreads::ScopedOpenMpThreads(int threads) {
  if (threads <= 0) return;
  previous_ = omp_get_max_threads();
  omp_set_num_threads(threads);
}

ScopedOpenMpThreads::~ScopedOpenMpThreads() {
  if (previous_ > 0) omp_set_num_threads(previous_);
}

}  // namespace occupancy_fusion
