// One thread that runs posted tasks in the order they were posted. The bus thread hands work
// here that must not delay the next request on the line: the wire log's file writes, and on a
// real-time bus thread its ROS publishing (roscpp's locks, subscribers' sockets).
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

namespace modbus_rtu_driver {

class TaskQueue {
 public:
  // At most `capacity` tasks wait; `thread_name` (15 characters at most) shows in top -H.
  explicit TaskQueue(size_t capacity = 1000, const std::string& thread_name = "modbus_publish");
  ~TaskQueue();  // stop()
  TaskQueue(const TaskQueue&) = delete;
  TaskQueue& operator=(const TaskQueue&) = delete;

  // Any thread. When `capacity` tasks already wait, the oldest is dropped (and counted): the
  // newest state matters more than an old one. After stop(), the task runs on the caller.
  void post(std::function<void()> task);
  // Runs the tasks still waiting, then ends the thread. Idempotent.
  void stop();
  uint64_t dropped() const;
  size_t highWater() const;  // the most tasks that ever waited at once

 private:
  void run();

  const size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::function<void()>> tasks_;
  bool stopping_ = false;
  uint64_t dropped_ = 0;
  size_t high_water_ = 0;
  std::thread thread_;
};

// Posts `task` to `queue`, or runs it here when there is none.
inline void postOrRun(TaskQueue* queue, std::function<void()> task) {
  if (queue)
    queue->post(std::move(task));
  else
    task();
}

}  // namespace modbus_rtu_driver
