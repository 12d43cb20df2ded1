#pragma once
// The service manager protocol (sd_notify(3), libsystemd): READY=1, WATCHDOG=1, STATUS=..., STOPPING=1 to the
// socket named by $NOTIFY_SOCKET. Without that variable (run by hand) every call does nothing.
//
// The watchdog: with WatchdogSec= systemd sets $WATCHDOG_USEC (and $WATCHDOG_PID); sd_watchdog_enabled() reads
// them. watchdog() sends WATCHDOG=1 at most every interval/4, so it can be called from every turn of a loop.

#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace agvslam::daemon {

class SystemdNotifier {
 public:
  SystemdNotifier();

  bool enabled() const { return enabled_; }  // $NOTIFY_SOCKET is set
  // 0 when the service has no watchdog.
  std::chrono::microseconds watchdog_interval() const { return watchdog_usec_; }

  void ready(const std::string& status);
  void status(const std::string& status);
  // Sends WATCHDOG=1 when a quarter of the interval has passed since the last one. Thread-safe.
  void watchdog();
  void stopping(const std::string& status);
  uint64_t watchdog_sent() const { return watchdog_sent_; }

 private:
  void send(const std::string& message);

  bool enabled_ = false;
  std::chrono::microseconds watchdog_usec_{0};
  std::mutex mutex_;
  std::chrono::steady_clock::time_point last_watchdog_{};
  uint64_t watchdog_sent_ = 0;
};

}  // namespace agvslam::daemon
