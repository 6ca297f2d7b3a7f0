// The publishing thread's queue: order kept, the poster never runs a task while the thread
// lives, a full queue drops its oldest task (counted), stop() runs what waits.
#include <gtest/gtest.h>
#include <pthread.h>

#include <atomic>
#include <future>
#include <mutex>
#include <thread>
#include <vector>

#include "modbus_rtu_driver/core/bus/task_queue.h"
#include "wait_for.h"

using namespace modbus_rtu_driver;

TEST(TaskQueue, RunsTasksInOrderOnItsOwnNamedThread) {
  TaskQueue queue(100, "test_queue");
  std::mutex m;
  std::vector<int> ran;
  std::vector<std::thread::id> threads;
  std::string name;
  for (int i = 0; i < 50; ++i)
    queue.post([&, i] {
      std::lock_guard<std::mutex> lock(m);
      ran.push_back(i);
      threads.push_back(std::this_thread::get_id());
      char buf[16] = {};
      pthread_getname_np(pthread_self(), buf, sizeof buf);
      name = buf;
    });
  ASSERT_TRUE(waitFor([&] {
    std::lock_guard<std::mutex> lock(m);
    return ran.size() == 50;
  }));
  std::lock_guard<std::mutex> lock(m);
  for (int i = 0; i < 50; ++i) EXPECT_EQ(ran[i], i);
  for (const auto& id : threads) EXPECT_NE(id, std::this_thread::get_id());
  EXPECT_EQ(name, "test_queue");
  EXPECT_EQ(queue.dropped(), 0u);
}

TEST(TaskQueue, FullQueueDropsTheOldestAndCountsIt) {
  TaskQueue queue(3);
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();
  std::atomic<bool> blocker_running{false};
  queue.post([&] {
    blocker_running = true;
    released.wait();
  });
  ASSERT_TRUE(waitFor([&] { return blocker_running.load(); }));
  std::mutex m;
  std::vector<int> ran;
  for (int i = 0; i < 5; ++i)  // 3 fit; 0 and 1 are pushed out by 3 and 4
    queue.post([&, i] {
      std::lock_guard<std::mutex> lock(m);
      ran.push_back(i);
    });
  EXPECT_EQ(queue.dropped(), 2u);
  EXPECT_EQ(queue.highWater(), 3u);
  release.set_value();
  queue.stop();
  EXPECT_EQ(ran, (std::vector<int>{2, 3, 4}));
}

TEST(TaskQueue, StopRunsWhatWaitsAndLaterPostsRunOnTheCaller) {
  auto queue = std::make_unique<TaskQueue>(100);
  std::atomic<int> count{0};
  for (int i = 0; i < 20; ++i) queue->post([&] { ++count; });
  queue->stop();
  EXPECT_EQ(count.load(), 20);
  std::thread::id where;
  queue->post([&] { where = std::this_thread::get_id(); });
  EXPECT_EQ(where, std::this_thread::get_id());
  queue->stop();  // idempotent
  queue.reset();
  EXPECT_EQ(count.load(), 20);
}
