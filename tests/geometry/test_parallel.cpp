// The OpenMP helpers: no exception may leave a parallel region (std::terminate), the first one
// becomes an exception of the call, and the other threads stop early.

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

#include "primlabel/geometry/features.hpp"
#include "primlabel/geometry/normals.hpp"
#include "primlabel/geometry/parallel.hpp"

namespace primlabel {
namespace {

TEST(Parallel, AnExceptionInABlockIsRethrownAfterTheRegion) {
  std::atomic<int> ran{0};
  const auto make_scratch = [] { return 0; };
  EXPECT_THROW(detail::for_each_block(10000, RunContext{2}, make_scratch,
                                      [&](int&, std::ptrdiff_t block) {
                                        ++ran;
                                        if (block == 3) throw std::runtime_error("block 3");
                                        // A block takes real time, as in the stages: the other
                                        // thread cannot finish all 10000 while the first throw
                                        // is being unwound (it did, now and then, on no work).
                                        std::this_thread::sleep_for(std::chrono::microseconds(200));
                                      }),
               std::runtime_error);
  EXPECT_LT(ran.load(), 10000);  // the others stopped early
}

TEST(Parallel, AFailingScratchIsAnExceptionToo) {
  const auto make_scratch = []() -> int { throw std::bad_alloc(); };
  EXPECT_THROW(
      detail::for_each_block(100, RunContext{2}, make_scratch, [](int&, std::ptrdiff_t) {}),
      std::bad_alloc);
}

TEST(Parallel, TheBarrierKeepsTheFirstException) {
  detail::ExceptionBarrier barrier;
#pragma omp parallel for num_threads(2)
  for (int i = 0; i < 1000; ++i)
    barrier.run([&] { throw std::invalid_argument("item " + std::to_string(i)); });
  EXPECT_TRUE(barrier.failed());
  EXPECT_THROW(barrier.rethrow(), std::invalid_argument);
}

// Every index once, whatever the schedule and the threads; each thread's scratch is merged once.
TEST(Parallel, ParallelForVisitsEveryIndexOnceAndMergesEveryScratch) {
  for (const detail::Schedule schedule : {detail::Schedule::Static(), detail::Schedule::Dynamic(7)})
    for (int threads : {1, 2, 3}) {
      std::vector<int> visits(1000, 0);
      long long merged_sum = 0, merged_count = 0;
      detail::parallel_for(
          1000, threads, schedule, [] { return 0LL; },
          [&](long long& sum, std::ptrdiff_t i) {
            ++visits[std::size_t(i)];
            sum += i;
          },
          [&](const long long& sum) {
            merged_sum += sum;
            ++merged_count;
          });
      EXPECT_EQ(std::count(visits.begin(), visits.end(), 1), 1000);
      EXPECT_EQ(merged_sum, 999LL * 1000 / 2);
      EXPECT_GE(merged_count, 1);  // one per thread OpenMP started
      EXPECT_LE(merged_count, threads);
    }
}

TEST(Parallel, AnExceptionInAMergeIsRethrown) {
  EXPECT_THROW(detail::parallel_for(
                   10, 2, detail::Schedule::Static(), [] { return 0; }, [](int&, std::ptrdiff_t) {},
                   [](int&) { throw std::runtime_error("merge"); }),
               std::runtime_error);
}

PointCloud grid_cloud() {
  PointCloud cloud;
  for (int i = 0; i < 100; ++i)
    for (int j = 0; j < 100; ++j) cloud.xyz.emplace_back(i * 0.01f, j * 0.01f, 0.0f);
  cloud.resize_unorganized(cloud.xyz.size());
  return cloud;
}

// A progress callback runs inside the parallel loops: what it throws reaches the caller.
TEST(Parallel, AThrowingProgressCallbackBecomesAnExceptionOfTheCall) {
  PointCloud cloud = grid_cloud();
  const NormalOptions normals;
  RunContext context{2};
  context.progress = [](std::size_t done, std::size_t) {
    if (done < 10000) throw std::runtime_error("progress says no");
  };
  EXPECT_THROW(estimate_normals(cloud, normals, context), std::runtime_error);
  estimate_normals(cloud, normals, RunContext{2});
  const FeatureOptions features;
  context.progress = [](std::size_t done, std::size_t) {
    if (done < 20000) throw std::runtime_error("progress says no");
  };
  EXPECT_THROW(compute_fpfh(cloud, features, context), std::runtime_error);
  EXPECT_THROW(compute_pfh(cloud, features, context), std::runtime_error);
}

}  // namespace
}  // namespace primlabel
