#include "agvslam/daemon/systemd_notifier.h"

#include <systemd/sd-daemon.h>

#include <spdlog/spdlog.h>
#include <cstdlib>

namespace agvslam::daemon {

SystemdNotifier::SystemdNotifier() {
  const char* socket = std::getenv("NOTIFY_SOCKET");
  enabled_ = socket != nullptr && socket[0] != '\0';
  uint64_t usec = 0;
  // > 0: the watchdog is on for this process ($WATCHDOG_USEC, and $WATCHDOG_PID is ours or unset).
  if (sd_watchdog_enabled(0, &usec) > 0) watchdog_usec_ = std::chrono::microseconds(usec);
}

void SystemdNotifier::send(const std::string& message) {
  if (!enabled_) return;
  const int rc = sd_notify(0, message.c_str());
  if (rc < 0) spdlog::warn("systemd: sd_notify failed: {}", rc);
}

void SystemdNotifier::ready(const std::string& status) { send("READY=1\nSTATUS=" + status); }

void SystemdNotifier::status(const std::string& status) { send("STATUS=" + status); }

void SystemdNotifier::watchdog() {
  if (!enabled_ || watchdog_usec_.count() == 0) return;
  const auto now = std::chrono::steady_clock::now();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (watchdog_sent_ > 0 && now - last_watchdog_ < watchdog_usec_ / 4) return;
    last_watchdog_ = now;
    ++watchdog_sent_;
  }
  send("WATCHDOG=1");
}

void SystemdNotifier::stopping(const std::string& status) { send("STOPPING=1\nSTATUS=" + status); }

}  // namespace agvslam::daemon
