// Admission: at most workers + queue requests at once, jobs on the worker threads, queued jobs
// can be abandoned, and the observer sees every count.

#include <gtest/gtest.h>

#include <atomic>
#include <future>
#include <thread>

#include "primlabel/service/admission.hpp"

namespace primlabel::service {
namespace {

TEST(Admission, AdmitsWorkersPlusQueueThenRefuses) {
  Admission admission(1, 2);
  EXPECT_EQ(admission.capacity(), 3);
  std::vector<Admission::Ticket> tickets;
  for (int i = 0; i < 3; ++i) {
    auto ticket = admission.try_admit();
    ASSERT_TRUE(ticket);
    tickets.push_back(std::move(*ticket));
  }
  EXPECT_FALSE(admission.try_admit());
  EXPECT_EQ(admission.admitted(), 3);
  tickets.pop_back();
  EXPECT_EQ(admission.admitted(), 2);
  EXPECT_TRUE(admission.try_admit());
}

TEST(Admission, RunsJobsOnWorkersAndAbandonsQueuedOnes) {
  std::atomic<int> last_admitted{-1}, last_queued{-1};
  Admission admission(1, 2, [&](int admitted, int queued) {
    last_admitted = admitted;
    last_queued = queued;
  });
  auto first = admission.try_admit();
  auto second = admission.try_admit();
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();
  std::atomic<bool> first_ran{false}, second_ran{false};
  auto running = admission.submit(*first, [&] {
    first_ran = true;
    released.wait();
  });
  while (!first_ran) std::this_thread::yield();
  auto waiting = admission.submit(*second, [&] { second_ran = true; });
  EXPECT_EQ(admission.queued(), 1);
  EXPECT_EQ(last_queued.load(), 1);
  EXPECT_FALSE(admission.abandon(running));  // already running
  EXPECT_TRUE(admission.abandon(waiting));
  EXPECT_TRUE(waiting->wait_for(std::chrono::milliseconds(0)));
  EXPECT_EQ(admission.queued(), 0);
  release.set_value();
  while (!running->wait_for(std::chrono::milliseconds(10))) {
  }
  EXPECT_FALSE(second_ran);
  EXPECT_EQ(last_admitted.load(), 2);
  first.reset();
  second.reset();
  EXPECT_EQ(last_admitted.load(), 0);
}

TEST(Admission, JobsRunInSubmissionOrderOnOneWorker) {
  Admission admission(1, 8);
  std::vector<int> order;
  std::mutex mutex;
  std::vector<std::shared_ptr<Admission::Job>> jobs;
  std::vector<Admission::Ticket> tickets;
  for (int i = 0; i < 5; ++i) {
    tickets.push_back(std::move(*admission.try_admit()));
    jobs.push_back(admission.submit(tickets.back(), [&, i] {
      std::lock_guard lock(mutex);
      order.push_back(i);
    }));
  }
  for (auto& job : jobs)
    while (!job->wait_for(std::chrono::milliseconds(10))) {
    }
  EXPECT_EQ(order, (std::vector<int>{0, 1, 2, 3, 4}));
}

}  // namespace
}  // namespace primlabel::service
