#include "modbus_rtu_driver/core/bus/task_queue.h"

#include <pthread.h>

#include <algorithm>
#include <utility>

namespace modbus_rtu_driver {

TaskQueue::TaskQueue(size_t capacity, const std::string& thread_name)
    : capacity_(std::max<size_t>(capacity, 1)) {
  thread_ = std::thread([this, name = thread_name.substr(0, 15)] {
    pthread_setname_np(pthread_self(), name.c_str());
    run();
  });
}

TaskQueue::~TaskQueue() {
  stop();
}

void TaskQueue::post(std::function<void()> task) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!stopping_) {
      if (tasks_.size() >= capacity_) {
        tasks_.pop_front();
        ++dropped_;
      }
      tasks_.push_back(std::move(task));
      high_water_ = std::max(high_water_, tasks_.size());
      wake_.notify_one();
      return;
    }
  }
  task();  // stopped: nobody else would run it
}

void TaskQueue::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
    wake_.notify_one();
  }
  if (thread_.joinable()) thread_.join();
}

uint64_t TaskQueue::dropped() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return dropped_;
}

size_t TaskQueue::highWater() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return high_water_;
}

void TaskQueue::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return stopping_ || !tasks_.empty(); });
    if (tasks_.empty()) return;  // stopping, and everything ran
    std::function<void()> task = std::move(tasks_.front());
    tasks_.pop_front();
    lock.unlock();
    task();
    lock.lock();
  }
}

}  // namespace modbus_rtu_driver
