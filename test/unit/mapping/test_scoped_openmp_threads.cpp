#include <gtest/gtest.h>
#include <omp.h>

#include <thread>

#include "occupancy_fusion/mapping/scoped_openmp_threads.h"

namespace occupancy_fusion {
namespace {

// The team size of a parallel region started here, as the integrators start theirs.
int teamSize() {
  int size = 0;
#pragma omp parallel
  {
#pragma omp single
    size = omp_get_num_threads();
  }
  return size;
}

// Puts this thread's OpenMP settings back for the other tests of the executable.
class ScopedOpenMpThreadsTest : public ::testing::Test {
 protected:
  ScopedOpenMpThreadsTest() { omp_set_dynamic(0); }  // team sizes exactly as asked
  ~ScopedOpenMpThreadsTest() override {
    omp_set_num_threads(threads_);
    omp_set_dynamic(dynamic_);
  }

 private:
  const int threads_ = omp_get_max_threads();
  const int dynamic_ = omp_get_dynamic();
};

TEST_F(ScopedOpenMpThreadsTest, RegionsInTheScopeUseTheCountAndTheOldOneComesBack) {
  omp_set_num_threads(3);
  {
    const ScopedOpenMpThreads scope(1);
    EXPECT_EQ(omp_get_max_threads(), 1);
    EXPECT_EQ(teamSize(), 1);
    {
      const ScopedOpenMpThreads inner(2);
      EXPECT_EQ(teamSize(), 2);
    }
    EXPECT_EQ(teamSize(), 1);
  }
  EXPECT_EQ(omp_get_max_threads(), 3);
  EXPECT_EQ(teamSize(), 3);
}

TEST_F(ScopedOpenMpThreadsTest, ZeroChangesNothing) {
  omp_set_num_threads(3);
  {
    const ScopedOpenMpThreads scope(0);
    EXPECT_EQ(omp_get_max_threads(), 3);
  }
  EXPECT_EQ(omp_get_max_threads(), 3);
}

// A nodelet manager's worker threads run every nodelet: one mapper's count must not reach a
// callback of another on another thread.
TEST_F(ScopedOpenMpThreadsTest, OtherThreadsKeepTheirOwnCount) {
  const auto count_on_new_thread = [] {
    int count = 0;
    std::thread other([&count] { count = omp_get_max_threads(); });
    other.join();
    return count;
  };
  const int before = count_on_new_thread();
  const ScopedOpenMpThreads scope(before + 1);
  EXPECT_EQ(teamSize(), before + 1);
  EXPECT_EQ(count_on_new_thread(), before);
}

}  // namespace
}  // namespace occupancy_fusion
