#include "agvslam/drivers/can/can_config.h"

#include <net/if.h>

#include <cstdio>
#include <sstream>

#include "agvslam/core/error.h"

namespace agvslam::drivers::can {

void CanConfig::validate(const std::string& source) const {
  if (interface.empty() || interface.size() >= IFNAMSIZ) {
    throw InputError(source, "can.interface", "expected a network interface name of 1.." + std::to_string(IFNAMSIZ - 1) +
                                                  " characters, e.g. can0");
  }
  const uint32_t max_id = extended_ids ? 0x1FFFFFFFU : 0x7FFU;
  if (base_id + kPoseFdOffset > max_id) {
    throw InputError(source, "can.base_id",
                     std::string("expected an id with base_id + 8 <= ") + (extended_ids ? "0x1FFFFFFF" : "0x7FF") +
                         (extended_ids ? "" : " (11-bit ids; set can.extended_ids for 29-bit ids)"));
  }
  if (!(rate_hz >= 0.0 && rate_hz <= 1000.0)) throw InputError(source, "can.rate_hz", "expected 0..1000 Hz (0: every pose)");
  if (status_every < 1 || status_every > 1000) throw InputError(source, "can.status_every", "expected an integer in 1..1000");
  if (reopen_min_ms < 1 || reopen_min_ms > 60000) {
    throw InputError(source, "can.reopen_min_ms", "expected an integer in 1..60000 (ms)");
  }
  if (reopen_max_ms < reopen_min_ms || reopen_max_ms > 600000) {
    throw InputError(source, "can.reopen_max_ms", "expected an integer in reopen_min_ms..600000 (ms)");
  }
}

std::string CanConfig::describe() const {
  char id[32];
  std::snprintf(id, sizeof id, "0x%X", base_id);
  std::ostringstream s;
  s << "can: interface " << interface << ", base id " << id << (extended_ids ? " (29-bit)" : " (11-bit)") << ", "
    << (fd ? "CAN FD frame base+8 (48 bytes)" : "classic frames base+0..4") << ", rate "
    << (rate_hz > 0.0 ? std::to_string(rate_hz) + " Hz" : std::string("every pose"));
  if (!fd) {
    s << ", velocity " << (send_velocity ? "on" : "off") << ", stddev " << (send_stddev ? "on" : "off")
      << ", status every " << status_every << " cycle(s)";
  }
  s << ", reopen back-off " << reopen_min_ms << ".." << reopen_max_ms << " ms";
  return s.str();
}

}  // namespace agvslam::drivers::can
