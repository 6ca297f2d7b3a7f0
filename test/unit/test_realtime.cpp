// Real-time scheduling of the bus thread: the hook runs on that thread before any job, and a
// refusal says which limit to raise.
#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>

#include <thread>

#include "modbus_rtu_driver/core/bus/bus_scheduler.h"
#include "modbus_rtu_driver/core/bus/realtime.h"

namespace modbus_rtu_driver {
namespace {

struct AnsweringTransport : Transport {
  Result execute(const Request&) override { return Result::success({0}); }
};

TEST(Realtime, ARefusalNamesTheLimit) {
  std::string error;
  // 100 is outside SCHED_FIFO's 1-99: refused by any kernel, for any user.
  std::thread([&] { EXPECT_FALSE(raiseToRealtime(100, &error)); }).join();
  EXPECT_NE(error.find("SCHED_FIFO priority 100 refused"), std::string::npos) << error;
  EXPECT_NE(error.find("rtprio limit"), std::string::npos) << error;
}

TEST(Realtime, AGrantedPriorityIsTheThreadsPolicy) {
  std::thread([] {
    std::string error;
    const bool granted = raiseToRealtime(10, &error);
    int policy = 0;
    sched_param param{};
    ASSERT_EQ(pthread_getschedparam(pthread_self(), &policy, &param), 0);
    if (granted) {
      EXPECT_EQ(policy, SCHED_FIFO);
      EXPECT_EQ(param.sched_priority, 10);
    } else {  // an unprivileged user without an rtprio limit: refused, and nothing changed
      EXPECT_EQ(policy, SCHED_OTHER);
      EXPECT_NE(error.find("rtprio limit"), std::string::npos) << error;
    }
  }).join();
}

TEST(Realtime, TheSchedulerRunsTheHookOnItsThreadBeforeAnyJob) {
  AnsweringTransport transport;
  BusScheduler::Options options;
  std::thread::id hook_thread;
  bool hook_ran_before_job = false;
  bool hook_ran = false;
  options.on_thread_start = [&] {
    hook_thread = std::this_thread::get_id();
    hook_ran = true;
  };
  BusScheduler scheduler(transport, options);
  scheduler.addDevice("d");
  scheduler.start();
  auto queued = scheduler.submit("d", [&](Transport& t) {
    hook_ran_before_job = hook_ran && std::this_thread::get_id() == hook_thread;
    return t.execute(Request::readCoils(1, 0, 1));
  });
  const Result r = queued.get();
  ASSERT_TRUE(r.ok()) << r.message;
  scheduler.stop();
  EXPECT_TRUE(hook_ran_before_job);
  EXPECT_NE(hook_thread, std::this_thread::get_id());
}

}  // namespace
}  // namespace modbus_rtu_driver
