// modbus_rtu_simulator as scripts run it: the ready line, SIGHUP, SIGTERM, frame log, bad
// configuration; and test/sim_control.py's command line against it.
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <fstream>
#include <sstream>
#include <thread>

#include "test_sim_helpers.h"

using namespace modbus_rtu_driver;
using namespace modbus_rtu_driver::simtest;

extern char** environ;

namespace {

#ifdef SIMULATOR_EXE
const char* kExe = SIMULATOR_EXE;
#else
const char* kExe = nullptr;  // the sanitizer build has no executable target
#endif

struct Process {
  pid_t pid = -1;
  int out = -1, err = -1;

  explicit Process(const std::vector<std::string>& args) {
    int o[2], e[2];
    if (pipe(o) != 0 || pipe(e) != 0) return;
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, o[1], 1);
    posix_spawn_file_actions_adddup2(&fa, e[1], 2);
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    if (posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ) != 0) pid = -1;
    posix_spawn_file_actions_destroy(&fa);
    close(o[1]);
    close(e[1]);
    out = o[0];
    err = e[0];
  }
  ~Process() {
    if (pid > 0 && waitpid(pid, nullptr, WNOHANG) == 0) {
      kill(pid, SIGKILL);
      waitpid(pid, nullptr, 0);
    }
    close(out);
    close(err);
  }
  // Everything the fd gives within `ms`, up to `until` appearing.
  static std::string readFor(int fd, int ms, const std::string& until = "") {
    std::string text;
    const auto end = SimClock::now() + std::chrono::milliseconds(ms);
    while (SimClock::now() < end && (until.empty() || text.find(until) == std::string::npos)) {
      pollfd p{fd, POLLIN, 0};
      if (poll(&p, 1, 50) <= 0) continue;
      char buf[512];
      const ssize_t n = read(fd, buf, sizeof buf);
      if (n <= 0) break;
      text.append(buf, static_cast<size_t>(n));
    }
    return text;
  }
  // Exit status, or -1 when it did not end within `ms`.
  int wait(int ms) {
    for (int i = 0; i < ms / 10; ++i) {
      int status = 0;
      if (waitpid(pid, &status, WNOHANG) == pid) {
        pid = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      std::this_thread::sleep_for(10ms);
    }
    return -1;
  }
};

// Output (stdout and stderr) and exit status of a shell command.
std::pair<std::string, int> shell(const std::string& command) {
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  std::string out;
  char buf[256];
  while (p && fgets(buf, sizeof buf, p)) out += buf;
  const int status = p ? pclose(p) : -1;
  return {out, WIFEXITED(status) ? WEXITSTATUS(status) : -1};
}

std::string control(const std::string& socket, const std::string& args) {
  return shell("python3 " REPO_DIR "/test/sim_control.py " + socket + " " + args).first;
}

bool exists(const std::string& path) {
  struct stat st {};
  return lstat(path.c_str(), &st) == 0;
}

}  // namespace

TEST(SimExecutable, ReadyLineFramesSighupAndACleanExit) {
  if (!kExe) GTEST_SKIP() << "built without the executable";
  ScratchDir dir;
  std::ofstream(dir / "sim.yaml") << "baud: 9600\ndevices:\n"
                                     "  - {type: ld58a08, address: 1}\n"
                                     "  - {type: lc_relay8, address: 255}\n";
  const std::string link = dir / "tty", socket = dir / "tty.ctl";
  Process sim({kExe, "--config", dir / "sim.yaml", "--link", link, "--state-file",
               dir / "state.yaml", "--verbose", "__name:=sim"});
  ASSERT_GT(sim.pid, 0);
  EXPECT_EQ(Process::readFor(sim.out, 10000, "\n"), "simulator ready on " + link + "\n");
  ASSERT_TRUE(exists(link));
  ASSERT_TRUE(exists(socket));

  // The Python client's command line.
  // The simulator's answer as it came (docs/simulator.md), "ok" included: a set says it worked.
  EXPECT_EQ(control(socket, "info"), "ok #0:ld58a08:1:9600:N #1:lc_relay8:255:9600:N\n");
  EXPECT_EQ(control(socket, "set 255 discrete_input 2 1"), "ok\n");
  EXPECT_EQ(control(socket, "get '#1' discrete_input 0 3"), "ok 0 0 1\n");
  EXPECT_EQ(control(socket, "power_cycle 255"), "ok\n");
  const auto [error, status] = shell("python3 " REPO_DIR "/test/sim_control.py " + socket + " x");
  EXPECT_EQ(status, 1);
  EXPECT_EQ(error, "x -> error unknown command 'x' (try help)\n");

  // A frame over the link, logged.
  {
    PtyClient client(link);
    EXPECT_EQ(client.exchange("01 06 00 FE 00 04 E9 F9", 8), "01 06 00 FE 00 04 E9 F9");
  }
  EXPECT_EQ(Process::readFor(sim.out, 5000, "tx 01 06 00 FE 00 04 E9 F9\n"),
            "rx 01 06 00 FE 00 04 E9 F9\ntx 01 06 00 FE 00 04 E9 F9\n");

  // SIGHUP: the power cycle takes the stored baud code.
  ASSERT_EQ(kill(sim.pid, SIGHUP), 0);
  std::string info;
  for (int i = 0; i < 100 && info.find("ld58a08:1:19200") == std::string::npos; ++i) {
    std::this_thread::sleep_for(20ms);
    info = control(socket, "info");
  }
  EXPECT_EQ(info, "ok #0:ld58a08:1:19200:N #1:lc_relay8:255:9600:N\n");

  ASSERT_EQ(kill(sim.pid, SIGTERM), 0);
  EXPECT_EQ(sim.wait(5000), 0);
  EXPECT_FALSE(exists(link));
  EXPECT_FALSE(exists(socket));
  std::ifstream state(dir / "state.yaml");
  std::stringstream text;
  text << state.rdbuf();
  EXPECT_NE(text.str().find("baud: 19200"), std::string::npos) << text.str();
}

TEST(SimExecutable, BadConfigurationAndOptionsAreRefused) {
  if (!kExe) GTEST_SKIP() << "built without the executable";
  ScratchDir dir;
  std::ofstream(dir / "bad.yaml") << "devices:\n  - {type: ld58a08, address: 300}\n";
  Process bad({kExe, "--config", dir / "bad.yaml", "--link", dir / "tty"});
  EXPECT_EQ(Process::readFor(bad.err, 5000, "\n"),
            "modbus_rtu_simulator: " + (dir / "bad.yaml") +
                ": devices[0]/address: 300 is outside 1-248 for ld58a08\n");
  EXPECT_EQ(bad.wait(5000), 1);
  EXPECT_FALSE(exists(dir / "tty"));
  Process option({kExe, "--config", dir / "bad.yaml", "--lnk", dir / "tty"});
  // The refusal names the option, then CLI11's help lists the options.
  const std::string refusal = Process::readFor(option.err, 5000, "--timestamps");
  EXPECT_EQ(refusal.rfind("modbus_rtu_simulator: unknown option --lnk\n", 0), 0u) << refusal;
  EXPECT_NE(refusal.find("Usage: modbus_rtu_simulator [OPTIONS]"), std::string::npos) << refusal;
  EXPECT_NE(refusal.find("--link PATH"), std::string::npos) << refusal;
  EXPECT_EQ(option.wait(5000), 2);
}

// Issue 33 item 2: a second simulator given a running one's --link (or --control) is refused
// with a message naming it and exits 1; the first keeps its link, its control socket and its
// line; and the one refused deletes nothing of the first's (docs/simulator.md).
TEST(SimExecutable, ASecondSimulatorOnARunningOnesLinkIsRefused) {
  if (!kExe) GTEST_SKIP() << "built without the executable";
  ScratchDir dir;
  std::ofstream(dir / "sim.yaml") << "baud: 9600\ndevices:\n  - {type: ld58a08, address: 1}\n";
  const std::string link = dir / "tty", socket = dir / "tty.ctl";
  Process first({kExe, "--config", dir / "sim.yaml", "--link", link});
  ASSERT_GT(first.pid, 0);
  ASSERT_EQ(Process::readFor(first.out, 10000, "\n"), "simulator ready on " + link + "\n");
  char target[256] = {};
  ASSERT_GT(readlink(link.c_str(), target, sizeof target - 1), 0);

  // The same link: refused, naming the link and the running one's pid.
  Process second({kExe, "--config", dir / "sim.yaml", "--link", link});
  ASSERT_GT(second.pid, 0);
  EXPECT_EQ(second.wait(10000), 1) << "the second simulator did not stop";
  const std::string refusal = Process::readFor(second.err, 2000, "\n");
  EXPECT_EQ(refusal, "modbus_rtu_simulator: " + link + " belongs to a running simulator (pid " +
                         std::to_string(first.pid) + ", which holds " + link +
                         ".lock): give each simulator its own --link\n");
  // Another link but the first's control socket: refused too, its own link removed again.
  Process third({kExe, "--config", dir / "sim.yaml", "--link", dir / "tty3", "--control", socket});
  ASSERT_GT(third.pid, 0);
  EXPECT_EQ(third.wait(10000), 1) << "the third simulator did not stop";
  EXPECT_EQ(Process::readFor(third.err, 2000, "\n"),
            "modbus_rtu_simulator: control socket " + socket +
                " belongs to a running simulator (it accepts connections): give each simulator "
                "its own --control\n");
  EXPECT_FALSE(exists(dir / "tty3"));

  // The first is untouched: its link to its pty, its control socket, its line.
  char now[256] = {};
  ASSERT_GT(readlink(link.c_str(), now, sizeof now - 1), 0);
  EXPECT_STREQ(now, target);
  EXPECT_EQ(control(socket, "info"), "ok #0:ld58a08:1:9600:N\n");
  {
    PtyClient client(link);
    EXPECT_EQ(client.exchange("01 06 00 FE 00 04 E9 F9", 8), "01 06 00 FE 00 04 E9 F9");
  }
  ASSERT_EQ(kill(first.pid, SIGTERM), 0);
  EXPECT_EQ(first.wait(5000), 0);
  EXPECT_FALSE(exists(link));
  EXPECT_FALSE(exists(socket));
  EXPECT_FALSE(exists(link + ".lock"));

  // Gone, it leaves nothing that refuses the next one (a killed one's lock file is no lock).
  Process again({kExe, "--config", dir / "sim.yaml", "--link", link});
  ASSERT_GT(again.pid, 0);
  EXPECT_EQ(Process::readFor(again.out, 10000, "\n"), "simulator ready on " + link + "\n");
  ASSERT_EQ(kill(again.pid, SIGKILL), 0);
  EXPECT_EQ(again.wait(5000), 128 + SIGKILL);
  Process after_kill({kExe, "--config", dir / "sim.yaml", "--link", link});
  ASSERT_GT(after_kill.pid, 0);
  EXPECT_EQ(Process::readFor(after_kill.out, 10000, "\n"), "simulator ready on " + link + "\n");
}
