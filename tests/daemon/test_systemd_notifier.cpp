// sd_notify for real: the test binds a unix datagram socket, points $NOTIFY_SOCKET at it and reads what
// SystemdNotifier sends (READY=1, STATUS=, WATCHDOG=1 rate-limited to a quarter of $WATCHDOG_USEC, STOPPING=1).
#include "agvslam/daemon/systemd_notifier.h"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <thread>

#include "common/test_data.h"

namespace agvslam::daemon {
namespace {

class NotifySocket {
 public:
  explicit NotifySocket(const std::string& path) : path_(path) {
    fd_ = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", path.c_str());
    bound_ = bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0;
    timeval tv{0, 200000};
    setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  }
  ~NotifySocket() {
    close(fd_);
    std::filesystem::remove(path_);
  }
  bool bound() const { return bound_; }
  // The next datagram, or "" after 200 ms without one.
  std::string next() {
    char buf[4096];
    const ssize_t n = recv(fd_, buf, sizeof buf, 0);
    return n > 0 ? std::string(buf, static_cast<std::size_t>(n)) : std::string();
  }

 private:
  std::string path_;
  int fd_ = -1;
  bool bound_ = false;
};

TEST(SystemdNotifier, SendsReadyStatusWatchdogAndStoppingToTheNotifySocket) {
  const std::string dir = test::make_temp_dir("agvslamd-notify");
  NotifySocket sock(dir + "/notify");
  ASSERT_TRUE(sock.bound());
  setenv("NOTIFY_SOCKET", (dir + "/notify").c_str(), 1);
  setenv("WATCHDOG_USEC", "400000", 1);  // 400 ms: WATCHDOG=1 at most every 100 ms
  unsetenv("WATCHDOG_PID");
  SystemdNotifier n;
  EXPECT_TRUE(n.enabled());
  EXPECT_EQ(n.watchdog_interval(), std::chrono::microseconds(400000));

  n.ready("first frame processed");
  EXPECT_EQ(sock.next(), "READY=1\nSTATUS=first frame processed");
  n.status("ok, 20.0 fps");
  EXPECT_EQ(sock.next(), "STATUS=ok, 20.0 fps");
  n.watchdog();
  n.watchdog();  // too soon: not sent
  EXPECT_EQ(sock.next(), "WATCHDOG=1");
  EXPECT_EQ(sock.next(), "");
  EXPECT_EQ(n.watchdog_sent(), 1U);
  std::this_thread::sleep_for(std::chrono::milliseconds(120));
  n.watchdog();
  EXPECT_EQ(sock.next(), "WATCHDOG=1");
  n.stopping("stopping: SIGTERM");
  EXPECT_EQ(sock.next(), "STOPPING=1\nSTATUS=stopping: SIGTERM");
  unsetenv("NOTIFY_SOCKET");
  unsetenv("WATCHDOG_USEC");
  std::filesystem::remove_all(dir);
}

TEST(SystemdNotifier, DoesNothingWithoutANotifySocketOrWatchdog) {
  unsetenv("NOTIFY_SOCKET");
  unsetenv("WATCHDOG_USEC");
  SystemdNotifier n;
  EXPECT_FALSE(n.enabled());
  EXPECT_EQ(n.watchdog_interval().count(), 0);
  n.ready("x");
  n.watchdog();
  EXPECT_EQ(n.watchdog_sent(), 0U);
}

TEST(SystemdNotifier, AWatchdogMeantForAnotherProcessIsNotOurs) {
  const std::string dir = test::make_temp_dir("agvslamd-notify-pid");
  NotifySocket sock(dir + "/notify");
  setenv("NOTIFY_SOCKET", (dir + "/notify").c_str(), 1);
  setenv("WATCHDOG_USEC", "400000", 1);
  setenv("WATCHDOG_PID", std::to_string(getpid() + 1).c_str(), 1);
  SystemdNotifier n;
  EXPECT_EQ(n.watchdog_interval().count(), 0);
  n.watchdog();
  EXPECT_EQ(sock.next(), "");
  unsetenv("NOTIFY_SOCKET");
  unsetenv("WATCHDOG_USEC");
  unsetenv("WATCHDOG_PID");
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace agvslam::daemon
