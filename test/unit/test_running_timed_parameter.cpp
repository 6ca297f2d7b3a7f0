// RunningTimedParameter (ros/running_timed_parameter.h), the writer of ~running_timed, with a
// write that blocks as a call to a master that is gone does (roscpp retries it until ROS's
// shutdown): the bus thread's keep() returns at once, only a device's newest list is written,
// flush() waits until its deadline, and the writer is destroyed without waiting for the write.
// The parameter server itself: rostest failsafe_items (test_06, test_06b).
#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "modbus_rtu_driver/ros/running_timed_parameter.h"

namespace modbus_rtu_driver {
namespace {

using Clock = std::chrono::steady_clock;

// A master: written lists in order; while `blocked`, a write waits (as roscpp's retries do).
struct Master {
  std::mutex mutex;
  std::condition_variable changed;
  bool blocked = false;
  int in_write = 0;
  std::vector<std::pair<std::string, std::vector<KeptTimedCommand>>> written;

  RunningTimedParameter::Write write() {
    return [this](const std::string& device, const std::vector<KeptTimedCommand>& kept) {
      std::unique_lock<std::mutex> lock(mutex);
      ++in_write;
      changed.notify_all();
      changed.wait(lock, [this] { return !blocked; });
      --in_write;
      written.emplace_back(device, kept);
      changed.notify_all();
    };
  }
  void setBlocked(bool b) {
    std::lock_guard<std::mutex> lock(mutex);
    blocked = b;
    changed.notify_all();
  }
  bool waitInWrite() {
    std::unique_lock<std::mutex> lock(mutex);
    return changed.wait_for(lock, std::chrono::seconds(10), [this] { return in_write > 0; });
  }
};

RunningTimedParameter::Read nothingKept() {
  return [](const std::string&) { return std::vector<KeptTimedCommand>{}; };
}

std::vector<KeptTimedCommand> flashOn(uint8_t channel) {
  KeptTimedCommand k;
  k.channel = channel;
  k.during = 1;
  k.ends = 1e9;
  return {k};
}

TEST(RunningTimedParameter, KeepDoesNotWaitAndOnlyTheNewestListIsWritten) {
  Master master;
  master.setBlocked(true);
  RunningTimedParameter parameter(nothingKept(), master.write());
  parameter.keep("relays", flashOn(4));
  ASSERT_TRUE(master.waitInWrite());
  // The master does not answer: the bus thread's calls return, the flush gives up at its deadline.
  parameter.keep("relays", flashOn(5));
  parameter.keep("relays", {});  // the stop's safe write ended the flash
  parameter.keep("pwm_board", flashOn(1));
  EXPECT_FALSE(parameter.flush(Clock::now() + std::chrono::milliseconds(200)));
  master.setBlocked(false);
  ASSERT_TRUE(parameter.flush(Clock::now() + std::chrono::seconds(10)));
  std::lock_guard<std::mutex> lock(master.mutex);
  ASSERT_EQ(master.written.size(), 3u);
  EXPECT_EQ(master.written[0].first, "relays");  // the write that was under way
  ASSERT_EQ(master.written[0].second.size(), 1u);
  EXPECT_EQ(master.written[0].second[0].channel, 4);
  // Then each device's newest list once: relays' two later lists are one write of the last.
  EXPECT_EQ(master.written[1].first, "pwm_board");
  EXPECT_EQ(master.written[2].first, "relays");
  EXPECT_TRUE(master.written[2].second.empty());
}

TEST(RunningTimedParameter, DestroyedWithoutWaitingForAWriteToAMasterThatDoesNotAnswer) {
  Master master;  // outlives the writer's detached thread until the write ends below
  master.setBlocked(true);
  {
    RunningTimedParameter parameter(nothingKept(), master.write());
    parameter.keep("relays", flashOn(4));
    ASSERT_TRUE(master.waitInWrite());
    parameter.keep("relays", {});
  }                          // would hang here if the destructor waited for the write
  master.setBlocked(false);  // the master answers (or roscpp gives up at ROS's shutdown)
  std::unique_lock<std::mutex> lock(master.mutex);
  ASSERT_TRUE(master.changed.wait_for(lock, std::chrono::seconds(10),
                                      [&] { return master.in_write == 0; }));
  // The thread ended after that write: the list kept after it is flush()'s, not the exit's.
  EXPECT_EQ(master.written.size(), 1u);
}

TEST(RunningTimedParameter, ReadsWhatThePreviousNodeKept) {
  Master master;
  RunningTimedParameter parameter(
      [](const std::string& device) {
        return device == "relays" ? flashOn(3) : std::vector<KeptTimedCommand>{};
      },
      master.write());
  ASSERT_EQ(parameter.read("relays").size(), 1u);
  EXPECT_EQ(parameter.read("relays")[0].channel, 3);
  EXPECT_TRUE(parameter.read("pdu").empty());
  EXPECT_TRUE(parameter.flush(Clock::now() + std::chrono::seconds(10)));  // nothing to write
}

}  // namespace
}  // namespace modbus_rtu_driver
